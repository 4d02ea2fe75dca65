"""Double hashing of stroke ids into a fixed-size table across frames (TAMISS sec. 4).

Private helper of :mod:`refnpr.formulas.tamiss` (which re-exports the public names).

The paper routes fragments by stroke id into the texels of an aggregate texture with double
hashing. To keep the routing parallel, the table is read-only during a frame; a stroke probes the
read-only table (last frame's) until it finds its own id or an empty slot, and writes its id to
that slot of a write-only table that becomes next frame's read-only table. Strokes that newly claim
the same empty slot collide: one id lands in the table, the others are "delayed by a frame" (and
their fragments are summed into the same slot in that frame).

Hash functions are 32-bit so that GPU backends can reproduce them bit for bit (WGSL has no 64-bit
integers): ids are unsigned 32-bit integers below ``EMPTY = 0xFFFFFFFF`` and, for a table of size
m = 2^j::

    h1(id) = lowbias32(id),  h2(id) = lowbias32(id ^ 0x9E3779B9) | 1   (odd, so coprime with m)
    slot_k(id) = (h1 + k * h2) mod 2^32 mod m

so the probe sequence of every id visits all m slots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refnpr._jit import njit

from .._face import elementwise, face
from .._validate import check_int, describe

__all__ = [
    "EMPTY",
    "FOUND",
    "CLAIM",
    "LOST",
    "hash_slot",
    "probe_table",
    "RouteResult",
    "StrokeHashTable",
]

#: Marker of an empty table slot (not a valid stroke id).
EMPTY = np.uint32(0xFFFFFFFF)
#: Probe outcomes: the id was in the table / an empty slot was reached first / gave up.
FOUND, CLAIM, LOST = 0, 1, 2


_MASK32 = np.uint64(0xFFFFFFFF)
_LB1, _LB2, _GOLD = np.uint64(0x7FEB352D), np.uint64(0x846CA68B), np.uint64(0x9E3779B9)
_S15, _S16 = np.uint64(15), np.uint64(16)


@njit
def _lowbias32(x):
    """Chris Wellons' lowbias32 integer hash of a 32-bit value held in a uint64 (the uint32
    wrapping products as products modulo 2^32)."""
    x = x ^ (x >> _S16)
    x = (x * _LB1) & _MASK32
    x = x ^ (x >> _S15)
    x = (x * _LB2) & _MASK32
    return x ^ (x >> _S16)


@njit
def _hash_slot(u, k, mask):
    u = np.uint64(u)
    h1 = _lowbias32(u)
    h2 = _lowbias32(u ^ _GOLD) | np.uint64(1)  # odd: coprime with the table size
    return np.int64((h1 + np.uint64(k) * h2) & np.uint64(mask))  # double hashing, mod 2^32


def _ids(ids) -> np.ndarray:
    arr = np.asarray(ids)
    if arr.dtype.kind not in "iu":
        raise TypeError(
            f"ids: expected integer stroke ids, got {describe(arr)}; pass an integer array"
        )
    if arr.size and (arr.min() < 0 or arr.max() >= int(EMPTY)):
        raise ValueError(
            f"ids: expected ids in [0, {int(EMPTY) - 1}] (32-bit, 0xFFFFFFFF marks empty slots), "
            f"got min {arr.min()}, max {arr.max()}; compress ids to 32 bits"
        )
    return arr.astype(np.uint32)


def _size(size) -> int:
    m = check_int("size", size, lo=2)
    if m & (m - 1):
        raise ValueError(
            f"size: expected a power of two (so that the odd step h2 visits every slot), got {m}; "
            f"use {1 << m.bit_length()}"
        )
    return m


@face(_hash_slot)
def hash_slot(ids, probe, size: int) -> np.ndarray:
    """Slot of the ``probe``-th double-hashing probe, (h1 + probe * h2) mod size.

    ``hash_slot.scalar(id, probe, size - 1)`` is the device function.

    Parameters
    ----------
    ids : (...) int, stroke ids in [0, 2^32 - 2]
    probe : int or (...) int >= 0, probe number k (broadcasts with ``ids``)
    size : int, a power of two >= 2

    Returns
    -------
    (...) int64 slot indices in [0, size).
    """
    u = _ids(ids)
    m = _size(size)
    k = np.asarray(probe)
    if k.dtype.kind not in "iu" or (k.size and k.min() < 0):
        raise ValueError(f"probe: expected non-negative integers, got {describe(k)}")
    return elementwise(hash_slot.scalar, np.int64, u, k.astype(np.int64), m - 1)


def probe_table(table, ids, *, max_probes: int | None = None):
    """Double-hashing lookup of ``ids`` in a read-only table.

    Probes k = 0, 1, ... until the slot holds the id (``FOUND``) or is ``EMPTY`` (``CLAIM``);
    after ``max_probes`` probes without either the id is ``LOST``.

    Parameters
    ----------
    table : (size,) uint32, ``EMPTY`` marks free slots
    ids : (n,) int
    max_probes : int >= 1, default ``size`` (a complete search)

    Returns
    -------
    slot : (n,) int64, -1 where lost
    status : (n,) int8, FOUND / CLAIM / LOST
    """
    tab = np.asarray(table)
    if tab.ndim != 1 or tab.dtype != np.uint32:
        raise TypeError(f"table: expected a 1D uint32 array, got {describe(tab)}")
    m = _size(tab.shape[0])
    u = _ids(ids).ravel()
    limit = m if max_probes is None else check_int("max_probes", max_probes, lo=1)
    slot = np.full(u.shape, -1, dtype=np.int64)
    status = np.full(u.shape, LOST, dtype=np.int8)
    active = np.arange(u.size)
    for k in range(limit):
        if active.size == 0:
            break
        s = hash_slot(u[active], k, m)
        v = tab[s]
        hit = v == u[active]
        free = v == EMPTY
        done = hit | free
        slot[active[done]] = s[done]
        status[active[hit]] = FOUND
        status[active[free]] = CLAIM
        active = active[~done]
    return slot, status


@dataclass(frozen=True)
class RouteResult:
    """Outcome of routing one frame's strokes (see :class:`StrokeHashTable`).

    Attributes
    ----------
    stroke_ids : (S,) uint32, the distinct ids of the frame, ascending
    slot : (S,) int64, the slot each stroke's fragments are summed into, -1 if lost
    found : (S,) bool, the id was in last frame's table
    delayed : (S,) bool, claimed an empty slot but another stroke's id was written there
    lost : (S,) bool, no slot within ``max_probes``
    contested : (S,) bool, the slot also receives another stroke's fragments this frame
    fragment_slot : (n,) int64, ``slot`` per input fragment
    """

    stroke_ids: np.ndarray
    slot: np.ndarray
    found: np.ndarray
    delayed: np.ndarray
    lost: np.ndarray
    contested: np.ndarray
    fragment_slot: np.ndarray

    @property
    def n_delayed(self) -> int:
        return int(self.delayed.sum())

    @property
    def n_lost(self) -> int:
        return int(self.lost.sum())

    @property
    def n_contested_slots(self) -> int:
        return int(np.unique(self.slot[self.contested]).size)


class StrokeHashTable:
    """The read-only / write-only hash table pair of TAMISS sec. 4, frame by frame.

    Parameters
    ----------
    size : int, a power of two >= 2 (texels of the aggregate texture)
    max_probes : int >= 1, probes before a stroke is lost (default 32)

    Notes
    -----
    :meth:`route_frame` routes one frame and swaps the tables. Write conflicts on the GPU are
    resolved in an unspecified order; here the smallest id wins, deterministically. A stroke whose
    probe meets an empty slot before its own id (because a stroke ahead of it on its probe sequence
    vanished) re-claims that earlier slot, exactly as on the GPU.
    """

    def __init__(self, size: int, *, max_probes: int = 32):
        self.size = _size(size)
        self.max_probes = check_int("max_probes", max_probes, lo=1)
        self._read = np.full(self.size, EMPTY, dtype=np.uint32)

    @property
    def read_table(self) -> np.ndarray:
        """(size,) uint32 copy of the current read-only table."""
        return self._read.copy()

    @property
    def occupancy(self) -> float:
        """Fraction of non-empty slots in the read-only table."""
        return float(np.count_nonzero(self._read != EMPTY)) / self.size

    def route_frame(self, ids) -> RouteResult:
        """Route the fragments of one frame, then make the new table the read-only one.

        Parameters
        ----------
        ids : (n,) int, the stroke id of every fragment of the frame (any order, repeated)
        """
        u = _ids(ids).ravel()
        sid, inverse = np.unique(u, return_inverse=True)
        slot, status = probe_table(self._read, sid, max_probes=self.max_probes)
        write = np.full(self.size, EMPTY, dtype=np.uint32)
        found = status == FOUND
        write[slot[found]] = sid[found]
        claim = np.flatnonzero(status == CLAIM)
        order = claim[np.argsort(slot[claim], kind="stable")]  # ids ascending within a slot
        first = np.ones(order.size, dtype=bool)
        first[1:] = slot[order[1:]] != slot[order[:-1]]
        write[slot[order[first]]] = sid[order[first]]  # the smallest claimant wins
        delayed = np.zeros(sid.size, dtype=bool)
        delayed[order[~first]] = True
        lost = status == LOST
        routed = slot[~lost]
        counts = np.bincount(routed, minlength=self.size)
        contested = ~lost & (counts[np.maximum(slot, 0)] > 1)
        self._read = write  # swap: the write-only table is read next frame
        return RouteResult(
            stroke_ids=sid,
            slot=slot,
            found=found,
            delayed=delayed,
            lost=lost,
            contested=contested,
            fragment_slot=slot[inverse.ravel()],
        )
