"""Aggregation of fragments by stroke id (TAMISS sec. 3.1 "summation", sec. 4).

Two routes to the same per-stroke sums:

* :func:`aggregate_exact` groups fragments by their 64-bit id (stable grouping; the CPU reference).
* :func:`aggregate_hashed` is the paper's GPU route: fragments are routed by double hashing of a
  32-bit key of the id into a fixed-size table (:class:`refnpr.formulas.tamiss.StrokeHashTable`:
  last frame's table read-only, this frame's write-only, swapped after the frame) and summed per
  slot. As a GPU would, each slot also min/max-blends the keys (and, here, the ids) it received;
  a slot that received more than one stroke this frame ("contested": new strokes that claimed the
  same empty slot) is skipped for the frame, so colliding new strokes appear one frame later.

Both follow the formula layer's two-pass scheme (``refnpr.formulas.tamiss.fit_fragments``): min/max
of t and of (x, y) per stroke, then the 15 regressors of each fragment in the centred parameter
s = normalize_t(t, t_min, t_max) and relative to the centre of the stroke's fragment bounding box,
summed in the fit dtype (float32 sums model GPU blending).

:class:`AggregateHistory` averages aggregates over the last frames (the paper's proposal against
jitter, sec. 4.1), in float64, each frame's sums :func:`recentre`-d to a common normalization
first (benign: the normalizations of consecutive frames are close).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace
from math import comb
from typing import Any

import numpy as np

from refnpr.formulas.tamiss import N_REGRESSORS, StrokeHashTable, aggregate, key32

from . import _kernels as K
from .gather import Fragments
from .motion import transport
from .state import rescale

__all__ = [
    "Aggregates",
    "HashStats",
    "aggregate_exact",
    "aggregate_hashed",
    "recentre",
    "AggregateHistory",
]


@dataclass(frozen=True, eq=False)
class HashStats:
    """What happened to one frame's strokes in the hash table.

    Attributes
    ----------
    table_size : int
    n_strokes : distinct stroke ids in the frame
    n_found : ids found in last frame's table
    n_claimed : ids that reached an empty slot first (new or moved strokes)
    n_delayed : claimants whose id lost the write race (enter the table next frame)
    n_contested : strokes whose slot received another stroke's fragments this frame (not drawn
        this frame; includes the winners of the races)
    n_lost : strokes that found no slot within ``max_probes`` (not drawn)
    n_aliased : strokes sharing their 32-bit key with another stroke of the frame
    occupancy : fraction of the new table's slots in use
    """

    table_size: int
    n_strokes: int
    n_found: int
    n_claimed: int
    n_delayed: int
    n_contested: int
    n_lost: int
    n_aliased: int
    occupancy: float

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True, eq=False)
class Aggregates:
    """Per-stroke sums (the aggregate texture's texels), S strokes sorted by id.

    Attributes
    ----------
    stroke_ids : (S,) int64
    count : (S,) int64, fragments per stroke
    t_min, t_max : (S,) fit dtype, range of t
    origin : (S, 2) fit dtype, centre of the fragments' bounding box (subtracted from x, y)
    moments : (S, 15) fit dtype, sums of ``fragment_regressors(s, x - o_x, y - o_y)``
    hash_stats : HashStats or None (hashed route only)
    """

    stroke_ids: np.ndarray
    count: np.ndarray
    t_min: np.ndarray
    t_max: np.ndarray
    origin: np.ndarray
    moments: np.ndarray
    hash_stats: HashStats | None = None

    def __len__(self) -> int:
        return int(self.stroke_ids.shape[0])

    @property
    def dtype(self) -> np.dtype:
        return self.moments.dtype

    def take(self, idx) -> Aggregates:
        """The strokes at ``idx`` (index or bool array)."""
        return replace(self, **{k: getattr(self, k)[idx] for k in ("stroke_ids", "count", *_SUMS)})

    def astype(self, dtype) -> Aggregates:
        """The same sums in another float dtype."""
        return replace(self, **{k: getattr(self, k).astype(np.dtype(dtype)) for k in _SUMS})


_SUMS = ("t_min", "t_max", "origin", "moments")


def _sums(keys, t, x, y, dtype):
    """(keys, count, lo, hi, origin, M) over groups of ``keys`` (int), summed in fragment order
    in ``dtype`` (the formula layer's ``normalize_t``, ``fragment_regressors``, ``aggregate``)."""
    keys = np.ascontiguousarray(keys, dtype=np.int64)
    uid, starts, perm = K.group_keys(keys)
    S = uid.shape[0]
    lo, hi = np.empty(S, dtype=dtype), np.empty(S, dtype=dtype)
    origin, M = np.empty((S, 2), dtype=dtype), np.empty((S, N_REGRESSORS), dtype=dtype)
    frags = tuple(np.ascontiguousarray(a, dtype=dtype) for a in (t, x, y))
    rows = np.empty((keys.shape[0], N_REGRESSORS), dtype=dtype)
    K.group_sums((perm, starts), frags, np.full(1, 0.5, dtype=dtype), (lo, hi, origin, M), rows)
    count = np.diff(starts).astype(np.int64)
    return uid, count, lo, hi, origin, M


def aggregate_exact(frags: Fragments, *, dtype=np.float32) -> Aggregates:
    """Exact per-stroke aggregates of a frame's fragments (group by id)."""
    return Aggregates(*_sums(frags.id, frags.t, frags.x, frags.y, np.dtype(dtype)))


def aggregate_hashed(frags: Fragments, table: StrokeHashTable, *, dtype=np.float32) -> Aggregates:
    """Aggregates through the double-hashed table (routes one frame and swaps ``table``).

    Fragments are summed per slot; slots that received more than one stroke this frame are
    dropped (see module docstring). Returned strokes are sorted by id, like
    :func:`aggregate_exact`, and carry :class:`HashStats` in ``hash_stats``.
    """
    dtype = np.dtype(dtype)
    keys = key32(frags.id)
    route = table.route_frame(keys)
    slot = route.fragment_slot
    kept = slot >= 0
    ids_k = frags.id[kept]
    slot_k = slot[kept]
    uid, count, lo, hi, origin, M = _sums(
        slot_k, frags.t[kept], frags.x[kept], frags.y[kept], dtype
    )
    _, kmin = aggregate(slot_k, keys[kept].astype(np.float64), op="min")
    _, kmax = aggregate(slot_k, keys[kept].astype(np.float64), op="max")
    # the stroke id of each slot (its first fragment's); exact ids decide contests below
    order = np.argsort(slot_k, kind="stable")
    first = ids_k[order][np.searchsorted(slot_k[order], uid)]
    single_key = kmin == kmax  # what a GPU can see: one key blended into the slot
    # strokes per slot among this frame's distinct ids
    sid_all = np.unique(frags.id)
    sid_slot = route.slot[np.searchsorted(route.stroke_ids, key32(sid_all))]
    per_slot = np.bincount(sid_slot[sid_slot >= 0], minlength=table.size)
    contested_slots = uid[per_slot[uid] > 1]
    n_contested = int(np.sum(per_slot[contested_slots]))
    _, key_counts = np.unique(key32(sid_all), return_counts=True)
    n_aliased = int(np.sum(key_counts[key_counts > 1]))
    valid = single_key & (per_slot[uid] == 1)
    stats = HashStats(
        table_size=table.size,
        n_strokes=int(sid_all.size),
        n_found=int(route.found.sum()),
        n_claimed=int(np.sum(~route.found & ~route.lost)),
        n_delayed=route.n_delayed,
        n_contested=n_contested,
        n_lost=int(np.sum(route.lost)),
        n_aliased=n_aliased,
        occupancy=table.occupancy,
    )
    sel = np.flatnonzero(valid)
    order_out = sel[np.argsort(first[sel], kind="stable")]
    return Aggregates(first, count, lo, hi, origin, M, stats).take(order_out)


def recentre(moments, t_min, t_max, origin, new_t_min, new_t_max, new_origin) -> np.ndarray:
    """Re-express centred sums in another normalization (all float64, per stroke).

    With t = c + h s (c, h: centre and half-width of [t_min, t_max]) the new parameter is
    s' = (t - c') / h' = alpha s + beta, alpha = h / h', beta = (c - c') / h', so
    sum s'^m = sum_j C(m, j) alpha^j beta^(m-j) sum s^j, likewise for the sums weighted by
    x - o, and sum s'^m (x - o') = sum s'^m (x - o) + (o - o') sum s'^m. Where h' = 0, s' = 0.

    Parameters
    ----------
    moments : (S, 15); t_min, t_max, new_t_min, new_t_max : (S,); origin, new_origin : (S, 2)

    Returns
    -------
    (S, 15) float64
    """
    M = np.asarray(moments, dtype=np.float64)
    alpha, beta = rescale(t_min, t_max, new_t_min, new_t_max)
    do = np.asarray(origin, np.float64) - np.asarray(new_origin, np.float64)
    out = np.zeros_like(M)

    def power(m, base):  # sum s'^m w from sum s^j w = base[:, j]
        acc = np.zeros(M.shape[0])
        for j in range(m + 1):
            acc = acc + comb(m, j) * alpha**j * beta ** (m - j) * base[:, j]
        return acc

    for m in range(7):
        out[:, m] = power(m, M[:, 0:7])
    for m in range(4):
        out[:, 7 + m] = power(m, M[:, 7:11]) + do[:, 0] * out[:, m]
        out[:, 11 + m] = power(m, M[:, 11:15]) + do[:, 1] * out[:, m]
    return out


class AggregateHistory:
    """Average aggregates over the last ``frames`` frames, per stroke id (sec. 4.1's proposal).

    :meth:`push` takes a frame's :class:`Aggregates` and returns the averaged aggregates of the
    strokes of *that* frame (float64): t range and origin are averaged over the frames in the
    window in which the stroke appeared, each frame's sums are :func:`recentre`-d to that averaged
    normalization and averaged. Averaged as they are (the paper's), the sums lag true motion by
    about (frames - 1) / 2 frames.

    ``anchors`` (one :class:`~refnpr.styles.tamiss.motion.StrokeAnchors` per window entry) with
    ``scene`` and ``size`` (the current frame's Scene and (width, height)): before averaging,
    each earlier frame's sums are moved along the exact surface motion to the current frame
    (:func:`~refnpr.styles.tamiss.motion.transport`, refnpr's motion compensation); a stroke
    that cannot be moved from a frame leaves that frame out of its average. Such a history
    serves one :meth:`push` (the frame of ``scene``).
    """

    def __init__(
        self,
        frames: int = 4,
        window: tuple = (),
        *,
        anchors: tuple | None = None,
        scene: Any = None,
        size: tuple[int, int] | None = None,
    ):
        if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or frames < 1:
            raise ValueError(f"frames: expected an integer >= 1, got {frames!r}")
        self.frames = int(frames)
        self._window: deque = deque(maxlen=self.frames)
        window = tuple(window)
        for past in window:  # a sequence state's window (the last frames' float64 sums)
            if not isinstance(past, Aggregates):
                raise TypeError(f"window: expected Aggregates, got {type(past).__name__}")
            self._window.append(past.astype(np.float64))
        self._anchors = None
        self._pushed = False
        if anchors is not None:
            anchors = tuple(anchors)
            if len(anchors) != len(window):
                raise ValueError(
                    f"anchors: expected one per window entry ({len(window)}), got {len(anchors)}"
                )
            if scene is None or size is None:
                raise ValueError("anchors: give the current frame's scene and size with them")
            self._anchors = anchors[len(anchors) - len(self._window) :]  # the kept entries
            self._scene, self._size = scene, (int(size[0]), int(size[1]))

    @property
    def window(self) -> tuple:
        """The aggregates in the window, oldest first (float64; at most ``frames``)."""
        return tuple(self._window)

    def push(self, agg: Aggregates) -> Aggregates:
        agg = agg.astype(np.float64)
        if self._anchors is not None:
            if self._pushed:
                raise ValueError(
                    "push: a history with anchors moves its window to one frame (its scene); "
                    "make a new AggregateHistory for each frame, as TamissStyle.run_frame does"
                )
            moved = [
                transport(past, anchor, self._scene, *self._size)
                for past, anchor in zip(self._window, self._anchors, strict=True)
            ]
        else:
            moved = [(past, None) for past in self._window]
        self._pushed = True
        self._window.append(agg)
        ids = agg.stroke_ids
        n = ids.size
        hits, acc_lo, acc_hi, acc_o = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros((n, 2))
        found = []
        entries = moved[max(0, len(moved) - self.frames + 1) :] + [(agg, None)]
        for past, ok in entries:
            if past.stroke_ids.size == 0:
                continue
            pos = np.minimum(np.searchsorted(past.stroke_ids, ids), past.stroke_ids.size - 1)
            hit = past.stroke_ids[pos] == ids
            if ok is not None:
                hit &= ok[pos]
            acc_lo[hit] += past.t_min[pos[hit]]
            acc_hi[hit] += past.t_max[pos[hit]]
            acc_o[hit] += past.origin[pos[hit]]
            hits += hit
            found.append((past, pos, hit))
        hits = np.maximum(hits, 1.0)
        lo, hi, origin = acc_lo / hits, acc_hi / hits, acc_o / hits[:, None]
        acc_m = np.zeros((n, 15))
        for past, pos, hit in found:
            i = pos[hit]
            acc_m[hit] += recentre(
                past.moments[i], past.t_min[i], past.t_max[i], past.origin[i],
                lo[hit], hi[hit], origin[hit],
            )  # fmt: skip
        return replace(agg, t_min=lo, t_max=hi, origin=origin, moments=acc_m / hits[:, None])
