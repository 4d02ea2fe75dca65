flat in vec4 o0;
flat in vec4 o1;
flat in vec4 o2;
flat in vec4 o3;
layout(location = 0) out vec4 r0;
layout(location = 1) out vec4 r1;
layout(location = 2) out vec4 r2;
layout(location = 3) out vec4 r3;
void main() {
    r0 = o0;
    r1 = o1;
    r2 = o2;
    r3 = o3;
}
