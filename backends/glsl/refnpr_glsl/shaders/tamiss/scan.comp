// Exclusive prefix sum of the per-sample fragment counts (stream compaction of the gathered
// fragments in sample order). stage 0: scan within blocks of 256; stage 1: scan the block sums
// (one invocation); stage 2: add each block's offset.
layout(local_size_x = 256) in;

layout(std430, binding = 0) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 1) buffer Offsets { uint offsets[]; };
layout(std430, binding = 10) buffer Blocks { uint blocks[]; };  // n_blocks + 1 (total last)

uniform int stage;
uniform uint n_items;
uniform uint n_blocks;

shared uint tmp[256];

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint l = gl_LocalInvocationID.x;
    uint b = gl_WorkGroupID.x;
    if (stage == 0) {
        uint c = i < n_items ? counts[i] : 0u;
        tmp[l] = c;
        barrier();
        for (uint off = 1u; off < 256u; off <<= 1) {
            uint v = l >= off ? tmp[l - off] : 0u;
            barrier();
            tmp[l] += v;
            barrier();
        }
        if (i < n_items) offsets[i] = tmp[l] - c;
        if (l == 255u) blocks[b] = tmp[l];
    } else if (stage == 1) {
        if (i != 0u) return;
        uint acc = 0u;
        for (uint k = 0u; k < n_blocks; k++) {
            uint v = blocks[k];
            blocks[k] = acc;
            acc += v;
        }
        blocks[n_blocks] = acc;
    } else {
        if (i < n_items) offsets[i] += blocks[b];
    }
}
