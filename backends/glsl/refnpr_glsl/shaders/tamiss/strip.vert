// One instance per stroke piece, in refnpr's order (ascending id, then segment): a quad over the
// piece's bounding box on the sample grid (array layout: NDC = 2 coord / size - 1 on both axes).
struct Piece { uint64_t id; int valid; int level; ivec4 bbox; vec4 color; };
layout(std430, binding = 18) readonly buffer Pieces { Piece pieces[]; };

uniform ivec2 grid;
flat out int piece;

void main() {
    piece = gl_InstanceID;
    Piece pe = pieces[gl_InstanceID];
    ivec4 bb = pe.bbox;
    if (pe.valid == 0 || bb.z < bb.x || bb.w < bb.y) {
        gl_Position = vec4(4.0, 4.0, 0.0, 1.0);
        return;
    }
    int c = gl_VertexID;
    vec2 corner = vec2((c & 1) != 0 ? bb.z + 1 : bb.x, (c & 2) != 0 ? bb.w + 1 : bb.y);
    gl_Position = vec4(corner / vec2(grid) * 2.0 - 1.0, 0.0, 1.0);
}
