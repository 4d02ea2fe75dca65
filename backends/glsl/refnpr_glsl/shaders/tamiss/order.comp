// The aggregated strokes in refnpr's order (ascending 64-bit id). stage 0: append every claimed
// slot to a list; stage 1: the rank of each listed stroke among all by id (a counting sort:
// S^2 comparisons, S = strokes of the frame), sorted[rank] = slot.
layout(local_size_x = 64) in;

layout(std430, binding = 11) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 12) readonly buffer Ids { uint64_t ids[]; };
layout(std430, binding = 15) buffer Counter { uint counter[]; };  // [2]: strokes
layout(std430, binding = 16) buffer List { uint list[]; };
layout(std430, binding = 17) writeonly buffer Sorted { uint sorted_[]; };

uniform int stage;
uniform uint n_slots;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (stage == 0) {
        if (i >= n_slots || keys[i] == 0xFFFFFFFFu) return;
        uint j = atomicAdd(counter[2], 1u);
        list[j] = i;
        return;
    }
    uint n = counter[2];
    if (i >= n) return;
    uint64_t mine = ids[list[i]];
    uint rank = 0u;
    for (uint j = 0u; j < n; j++) {
        if (ids[list[j]] < mine) rank++;
    }
    sorted_[rank] = list[i];
}
