// The paper's aggregation table across frames (TAMISS sec. 4; refnpr formulas/tamiss/hashing.py
// StrokeHashTable, aggregation = "hashed"): last frame's table is read-only, this frame's is
// write-only. stage 0 (per fragment): probe the read table with the double-hashing sequence of
// key32(id) until the key (found) or an empty slot (claim); write the key into the write table
// with atomicMin (of claimants of one empty slot the smallest key wins; the others are delayed
// a frame), and route the fragment to that slot. After the last routing: stages 1-3 find, per
// slot, the smallest 64-bit id among its fragments and whether any other id arrived
// (a contested slot is not drawn this frame); stage 4 (per slot) marks the drawable slots.
layout(local_size_x = 64) in;

struct Frag { uint64_t id; float t; float x; float y; uint meta; };

layout(std430, binding = 2) readonly buffer Frags { Frag frags[]; };
layout(std430, binding = 11) buffer Keys { uint keys[]; };        // stage 4: drawable marks
layout(std430, binding = 12) buffer Ids { uint64_t ids[]; };      // the slot's stroke id
layout(std430, binding = 14) buffer State { ivec2 state[]; };     // (slot or -1, status)
layout(std430, binding = 22) readonly buffer ReadT { uint rtab[]; };
layout(std430, binding = 23) buffer WriteT { uint wtab[]; };
layout(std430, binding = 24) buffer Owner { uint owner[]; };      // hi, lo, bad, used per slot

uniform int stage;
uniform uint n_items;
uniform uint table_mask;
uniform int max_probes;

const uint EMPTY = 0xFFFFFFFFu;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n_items) return;
    if (stage == 4) {
        bool ok = owner[4u * i + 3u] != 0u && owner[4u * i + 2u] == 0u;
        keys[i] = ok ? 0u : EMPTY;
        return;
    }
    uint64_t sid = frags[i].id;
    uint hi = uint(sid >> 32), lo = uint(sid & 0xFFFFFFFFUL);
    if (stage == 0) {
        uint key = key32(sid);
        uint h1 = lowbias32(key);
        uint h2 = lowbias32(key ^ 0x9E3779B9u) | 1u;
        for (int k = 0; k < max_probes; k++) {
            uint s = (h1 + uint(k) * h2) & table_mask;
            uint v = rtab[s];
            if (v == key || v == EMPTY) {
                atomicMin(wtab[s], key);
                state[i] = ivec2(int(s), v == key ? 0 : 1);
                return;
            }
        }
        state[i] = ivec2(-1, 2);
        return;
    }
    int s = state[i].x;
    if (s < 0) return;
    uint o = 4u * uint(s);
    if (stage == 1) {
        atomicMin(owner[o], hi);
        atomicOr(owner[o + 3u], 1u);
    } else if (stage == 2) {
        if (owner[o] == hi) atomicMin(owner[o + 1u], lo);
    } else {
        if (owner[o] == hi && owner[o + 1u] == lo) ids[s] = sid;
        else atomicOr(owner[o + 2u], 1u);
    }
}
