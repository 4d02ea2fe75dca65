// Aggregation routing by double hashing (TAMISS sec. 4): each fragment finds the slot of its
// stroke in a table of 2^j slots, probing slot_k = (h1 + k h2) mod 2^j with h1 = lowbias32(key),
// h2 = lowbias32(key ^ 0x9E3779B9) | 1 and key = key32(id) (refnpr formulas/tamiss/hashing.py).
// Exact route: slots are claimed with atomicCompSwap on the key; the claimant stores the full
// 64-bit id, so that strokes sharing a 32-bit key (aliases) probe on. One round per dispatch: a
// fragment that meets its key in a slot claimed in this round (id not yet visible) retries in
// the next round; rounds repeat until every fragment has its slot.
layout(local_size_x = 64) in;

struct Frag { uint64_t id; float t; float x; float y; uint meta; };

layout(std430, binding = 2) readonly buffer Frags { Frag frags[]; };
layout(std430, binding = 11) coherent buffer Keys { uint keys[]; };
layout(std430, binding = 12) coherent buffer Ids { uint64_t ids[]; };
layout(std430, binding = 13) coherent buffer Rounds { uint claim_round[]; };
layout(std430, binding = 14) buffer State { ivec2 state[]; };   // (slot, next probe)
layout(std430, binding = 15) buffer Counter { uint counter[]; }; // unresolved, lost, ...

uniform uint n_frags;
uniform uint table_mask;
uniform uint round_;
uniform int max_probes;

const uint EMPTY = 0xFFFFFFFFu;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n_frags) return;
    ivec2 st = state[i];
    if (st.x != -1) return;  // resolved (>= 0) or lost (-2)
    uint64_t sid = frags[i].id;
    uint key = key32(sid);
    uint h1 = lowbias32(key);
    uint h2 = lowbias32(key ^ 0x9E3779B9u) | 1u;
    for (int k = st.y; k < max_probes; k++) {
        uint s = (h1 + uint(k) * h2) & table_mask;
        uint kv = atomicAdd(keys[s], 0u);
        if (kv == EMPTY) {
            uint prev = atomicCompSwap(keys[s], EMPTY, key);
            if (prev == EMPTY) {
                ids[s] = sid;
                memoryBarrierBuffer();
                atomicExchange(claim_round[s], round_);
                state[i] = ivec2(int(s), k);
                return;
            }
            kv = prev;
        }
        if (kv == key) {
            uint cr = atomicAdd(claim_round[s], 0u);
            if (cr < round_) {
                if (ids[s] == sid) {
                    state[i] = ivec2(int(s), k);
                    return;
                }
                continue;  // an alias: another stroke with this key holds the slot
            }
            state[i] = ivec2(-1, k);  // claimed in this round: retry here next round
            atomicAdd(counter[0], 1u);
            return;
        }
    }
    state[i] = ivec2(-2, max_probes);
    atomicAdd(counter[1], 1u);
}
