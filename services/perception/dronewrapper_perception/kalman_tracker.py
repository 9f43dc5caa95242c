"""The stronger follow-person tracker: Kalman motion + colour appearance, Hungarian association.

One constant-velocity Kalman filter per track plus a colour-histogram appearance model,
Mahalanobis and appearance gating, Hungarian association; tracks coast through occlusions up to
``max_coast_s``; the target keeps its track id while its track lives. The target is also
re-identified by appearance: when the camera itself moves (the drone pitches, climbs or turns)
a person standing still jumps in the image beyond the motion gate, so a coasting target track
may take an unoccluded detection of the same appearance within a loose spatial gate (also one a
young track took: the target re-detected while coming out from behind someone); and once the
target's track is gone, the new target is the person who looks like it (never simply the most
confident detection, which may be a passer-by). "Looks like it" is judged against the target's
own look variation, so a passer-by in similar colours is not taken for it. The first target is
the person the drone looks at (score x box height x closeness to the image centre line), not
merely the most confident. Everything reasons in seconds, never in frames.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dronewrapper_perception.appearance import bhattacharyya
from dronewrapper_perception.assignment import INFEASIBLE, assign
from dronewrapper_perception.detection import Detection
from dronewrapper_perception.kalman_filter import BoxKalmanFilter
from dronewrapper_perception.track_result import TrackingResult

CHI2_4DOF_99 = 13.277
"""99 % quantile of the chi-square distribution with 4 degrees of freedom (the motion gate)."""


def prominence(det: Detection, image_wh: tuple[int, int] | None = None) -> float:
    """How strongly a detection asks to be followed first: the person the drone looks at.

    Score x box height (px: nearer people are taller) x closeness of the box centre to the
    image's vertical centre line (1 there, falling linearly to 0.05 at the side edges; 1 when
    the image size is not known).
    """
    x1, top, x2, bottom = det.box_xyxy
    centrality = 1.0
    if image_wh is not None and image_wh[0] > 0:
        half = image_wh[0] / 2
        centrality = max(0.05, 1.0 - abs((x1 + x2) / 2 - half) / half)
    return float(det.score) * max(0.0, bottom - top) * centrality


def _cxcywh(det: Detection) -> np.ndarray:
    x1, y1, x2, y2 = det.box_xyxy
    return np.array([(x1 + x2) / 2, (y1 + y2) / 2, x2 - x1, y2 - y1], dtype=np.float64)


def _overlap_fraction(box: Sequence[float], other: Sequence[float]) -> float:
    """Fraction of ``box``'s area covered by ``other``."""
    ix = max(0.0, min(box[2], other[2]) - max(box[0], other[0]))
    iy = max(0.0, min(box[3], other[3]) - max(box[1], other[1]))
    area = max(1e-9, (box[2] - box[0]) * (box[3] - box[1]))
    return ix * iy / area


@dataclass
class Track:
    """One tracked object: its filter, appearance and bookkeeping (times in s, boxes in px)."""

    track_id: str
    kf: BoxKalmanFilter
    appearance: np.ndarray | None
    class_id: int
    last_seen: float
    last_box: np.ndarray
    """The last detected box (cx, cy, w, h)."""
    hits: int = 1
    born: float = 0.0
    """Time (s) of the track's first detection."""
    self_distance: float | None = None
    """Running mean Bhattacharyya distance of the track's own unoccluded views to its model:
    how much this person's look varies (walking, turning); the re-identification gate."""
    appearance_t: float | None = None
    """Time (s) of the last view blended into ``appearance``."""


class KalmanTracker:
    """Multi-object tracker: Kalman motion + colour appearance, Hungarian association.

    Args:
        max_coast_s: a track not seen for longer is deleted (occlusions shorter survive).
        motion_gate: squared Mahalanobis distance beyond which a detection cannot match.
        appearance_gate: Bhattacharyya distance beyond which a detection cannot match.
        appearance_weight: 0..1 share of appearance in the matching cost (rest is motion).
        appearance_time_constant_s: how fast a track's histogram follows new, unoccluded views:
            a view seen ``dt`` s after the previous one is blended with weight
            ``1 - exp(-dt / appearance_time_constant_s)``, so the model adapts at the same pace
            in seconds whatever the frame rate.
        occlusion_overlap: a detection covered more than this fraction by another detection
            does not update its track's appearance (it is mixed with the other person).
        min_hits: detections a new track needs before its misses are tolerated.
        recent_s: tracks seen within this time are matched first (their prediction is sharper
            than a coasting track's, so a coasting track cannot steal their detection).
        reid_distance: how far (in box heights, centre to centre) from its predicted or last
            seen box a detection may be re-identified as the coasting target by appearance.
        reid_self_factor, reid_gate_min: the re-identification appearance gate is
            ``reid_self_factor`` x the target's own look variation (``Track.self_distance``) plus
            ``reid_gate_min``, at most ``appearance_gate``: a person standing still in even light
            is recognised only by a near-identical look, a walking one with more tolerance. A
            passer-by who merely dresses in similar colours is not taken for the target.
        reid_size_ratio: the re-identified box's height may differ from the track's by at most
            this factor.
        forget_target_s: after this long without the target, its remembered appearance is
            dropped and the next target is picked as the first one was (:func:`prominence`).
    """

    needs_appearance = True

    def __init__(
        self,
        *,
        max_coast_s: float = 2.0,
        motion_gate: float = CHI2_4DOF_99,
        appearance_gate: float = 0.6,
        appearance_weight: float = 0.5,
        appearance_time_constant_s: float = 1.0,
        occlusion_overlap: float = 0.15,
        min_hits: int = 2,
        recent_s: float = 0.25,
        reid_distance: float = 1.5,
        reid_size_ratio: float = 1.5,
        reid_self_factor: float = 3.0,
        reid_gate_min: float = 0.15,
        forget_target_s: float = 10.0,
    ) -> None:
        if appearance_time_constant_s <= 0:
            raise ValueError("appearance_time_constant_s must be > 0")
        self.max_coast_s = max_coast_s
        self.motion_gate = motion_gate
        self.appearance_gate = appearance_gate
        self.appearance_weight = appearance_weight
        self.appearance_time_constant_s = appearance_time_constant_s
        self.occlusion_overlap = occlusion_overlap
        self.min_hits = min_hits
        self.recent_s = recent_s
        self.reid_distance = reid_distance
        self.reid_size_ratio = reid_size_ratio
        self.reid_self_factor = reid_self_factor
        self.reid_gate_min = reid_gate_min
        self.forget_target_s = forget_target_s
        self.tracks: list[Track] = []
        self.target_id = ""
        self._target_appearance: np.ndarray | None = None
        self._target_gate = appearance_gate
        self._target_seen = -np.inf
        self._ids = itertools.count(1)

    def reset(self) -> None:
        """Drop every track, the target and its remembered appearance."""
        self.tracks.clear()
        self.target_id = ""
        self._target_appearance = None
        self._target_gate = self.appearance_gate
        self._target_seen = -np.inf

    def reid_gate(self, track: Track) -> float:
        """The appearance distance within which ``track`` is re-identified (see the class)."""
        variation = track.self_distance if track.self_distance is not None else 0.0
        gate = self.reid_self_factor * variation + self.reid_gate_min
        return float(min(self.appearance_gate, gate))

    def _cost(self, track: Track, boxes: np.ndarray, dets, features) -> np.ndarray:
        d2 = track.kf.mahalanobis_sq(boxes)
        motion = d2 / self.motion_gate
        cost = np.empty(len(dets))
        for j, det in enumerate(dets):
            if d2[j] > self.motion_gate or det.class_id != track.class_id:
                cost[j] = INFEASIBLE
                continue
            feature = features[j] if features is not None else None
            if track.appearance is None or feature is None:
                cost[j] = motion[j]
                continue
            app = bhattacharyya(track.appearance, feature)
            if app > self.appearance_gate:
                cost[j] = INFEASIBLE
                continue
            w = self.appearance_weight
            cost[j] = (1 - w) * motion[j] + w * app / self.appearance_gate
        return cost

    def _occluded(self, j: int, dets: Sequence[Detection]) -> bool:
        box = dets[j].box_xyxy
        return any(
            _overlap_fraction(box, other.box_xyxy) > self.occlusion_overlap
            for k, other in enumerate(dets)
            if k != j
        )

    def update(self, detections, t, features=None, image_wh=None) -> TrackingResult:
        dets = list(detections)
        if features is not None and len(features) != len(dets):
            raise ValueError("features must have one entry per detection")
        self.tracks = [tr for tr in self.tracks if t - tr.last_seen <= self.max_coast_s]
        for track in self.tracks:
            track.kf.predict(t)
        boxes = np.array([_cxcywh(d) for d in dets]).reshape(-1, 4)
        # two passes: tracks seen recently first (less uncertain), then coasting ones
        ids = ["" for _ in dets]
        unmatched = set(range(len(dets)))
        fresh = [tr for tr in self.tracks if t - tr.last_seen <= self.recent_s]
        coasting = [tr for tr in self.tracks if t - tr.last_seen > self.recent_s]
        for group in (fresh, coasting):
            cols = sorted(unmatched)
            if not group or not cols:
                continue
            sub_dets = [dets[j] for j in cols]
            sub_feats = [features[j] for j in cols] if features is not None else None
            cost = np.vstack([self._cost(tr, boxes[cols], sub_dets, sub_feats) for tr in group])
            for row, col in assign(cost):
                track, j = group[row], cols[col]
                self._apply(track, j, dets, boxes, features, t)
                ids[j] = track.track_id
                unmatched.discard(j)
        found = self._reidentify_target(unmatched, ids, dets, boxes, features, t)
        if found is not None:
            ids[found] = self.target_id
            unmatched.discard(found)
        for j in sorted(unmatched):
            feature = None if features is None or self._occluded(j, dets) else features[j]
            track = Track(
                track_id=f"t{next(self._ids)}",
                kf=BoxKalmanFilter(boxes[j], t),
                appearance=feature,
                appearance_t=t if feature is not None else None,
                class_id=dets[j].class_id,
                last_seen=t,
                last_box=boxes[j],
                born=t,
            )
            self.tracks.append(track)
            ids[j] = track.track_id
        self.tracks = [
            tr
            for tr in self.tracks
            if (t - tr.last_seen <= self.max_coast_s)
            and (tr.hits >= self.min_hits or tr.last_seen == t)
        ]
        return self._select_target(dets, ids, features, t, image_wh)

    def _reidentify_target(
        self, unmatched: set[int], ids: list[str], dets, boxes, features, t
    ) -> int | None:
        """Give the coasting target track the unoccluded detection that looks most like it.

        The detection may be unmatched, or held by a track born after the target was last seen
        (the target itself, re-detected as somebody new while it came out from behind a
        passer-by); that young track is then dropped. Only a detection of the target's class,
        within ``reid_distance`` box heights of the track's predicted or last seen centre (a
        coasting prediction drifts on whatever velocity the camera's motion gave it), of a
        similar height, within the target's re-identification gate (:meth:`reid_gate`) and not
        more like another unseen track, may be taken; its motion filter restarts from that box
        (the jump was the camera's, not the person's velocity). Returns the detection's index,
        or None.
        """
        track = self._track(self.target_id)
        if track is None or track.last_seen == t or track.appearance is None or features is None:
            return None
        height = track.last_box[3]
        centres = np.array([track.kf.box_cxcywh[:2], track.last_box[:2]])

        def near_and_alike_in_size(j: int) -> bool:
            size_ratio = max(boxes[j][3], 1.0) / max(height, 1.0)
            offset = np.linalg.norm(centres - boxes[j][:2], axis=1).min()
            return (
                dets[j].class_id == track.class_id
                and 1 / self.reid_size_ratio <= size_ratio <= self.reid_size_ratio
                and offset <= self.reid_distance * height
            )

        young = {
            j: tr
            for j, tid in enumerate(ids)
            if tid and (tr := self._track(tid)) is not None and tr.born > track.last_seen
        }
        candidates = [j for j in sorted(unmatched | set(young)) if near_and_alike_in_size(j)]
        missing = [tr for tr in self.tracks if tr is not track and tr.last_seen != t]
        best = self._most_alike(
            track.appearance, self.reid_gate(track), candidates, dets, features, missing
        )
        if best is not None:
            if best in young:
                self.tracks.remove(young[best])
            track.kf = BoxKalmanFilter(boxes[best], t)
            self._apply(track, best, dets, boxes, features, t, measured=False)
        return best

    def _track(self, track_id: str) -> Track | None:
        return next((tr for tr in self.tracks if tr.track_id == track_id), None)

    def _most_alike(
        self,
        appearance: np.ndarray,
        gate: float,
        candidates,
        dets,
        features,
        others: Sequence[Track] = (),
    ) -> int | None:
        """Index of the unoccluded candidate detection nearest ``appearance`` (Bhattacharyya)
        within ``gate``, or None. A candidate that looks more like one of ``others`` (tracks not
        seen in this frame: it may be one of them) than like ``appearance`` is left out."""
        if features is None:
            return None
        best, best_distance = None, gate
        for j in candidates:
            if features[j] is None or self._occluded(j, dets):
                continue
            distance = bhattacharyya(appearance, features[j])
            if distance > best_distance:
                continue
            if any(
                other.appearance is not None
                and bhattacharyya(other.appearance, features[j]) < distance
                for other in others
            ):
                continue
            best, best_distance = j, distance
        return best

    def _apply(
        self, track: Track, j: int, dets, boxes, features, t: float, *, measured: bool = True
    ) -> None:
        """Record detection ``j`` on ``track`` (``measured``: also correct its filter)."""
        if measured:
            track.kf.update(boxes[j])
        track.last_seen = t
        track.last_box = boxes[j]
        track.hits += 1
        feature = features[j] if features is not None else None
        if feature is None or self._occluded(j, dets):
            return
        if track.appearance is None:
            track.appearance, track.appearance_t = feature, t
            return
        distance = bhattacharyya(track.appearance, feature)
        dt = max(0.0, t - (track.appearance_t if track.appearance_t is not None else t))
        rate = 1.0 - float(np.exp(-dt / self.appearance_time_constant_s))
        if track.self_distance is None:
            track.self_distance = distance
        else:
            track.self_distance += max(rate, 0.05) * (distance - track.self_distance)
        mixed = (1 - rate) * track.appearance + rate * feature
        track.appearance = mixed / max(float(mixed.sum()), 1e-12)
        track.appearance_t = t

    def _select_target(
        self, dets: Sequence[Detection], ids: list[str], features, t: float, image_wh
    ) -> TrackingResult:
        alive = {tr.track_id for tr in self.tracks}
        if self.target_id not in alive:
            self.target_id = self._pick_target(dets, ids, features, t, image_wh)
        index = ids.index(self.target_id) if self.target_id in ids else None
        if index is not None:
            track = self._track(self.target_id)
            if track is not None and track.appearance is not None:
                self._target_appearance = track.appearance  # replaced on update, never mutated
                self._target_gate = self.reid_gate(track)
            self._target_seen = t
        visible = self.target_id if index is not None else ""
        return TrackingResult(tuple(ids), visible, index)

    def _pick_target(
        self, dets: Sequence[Detection], ids: list[str], features, t: float, image_wh
    ) -> str:
        """A new target's track id ("" = none this frame).

        While the lost target's appearance is remembered (seen within ``forget_target_s``), only
        an unoccluded detection within its re-identification gate (:meth:`reid_gate`, as it
        was when last seen) may become the target, the most alike first. Otherwise (the first
        pick, no appearance, or forgotten): the most prominent person (:func:`prominence`: the
        one the drone looks at), so a person far behind, or passing at the side, cannot win on
        a slightly higher confidence.
        """
        if not dets:
            return ""
        memory = self._target_appearance
        if memory is not None and t - self._target_seen <= self.forget_target_s:
            best = self._most_alike(memory, self._target_gate, range(len(dets)), dets, features)
            return ids[best] if best is not None else ""
        self._target_appearance = None
        return ids[max(range(len(dets)), key=lambda i: prominence(dets[i], image_wh))]
