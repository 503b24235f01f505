"""Plane geometry for checking a drawing: segments, polylines and axis-aligned boxes.

A box is (centre, half-sizes); a segment is (start, end). The drawing uses these to pick
a clean layout among a few, and the tests use them to check every shipped model's picture.
"""

from __future__ import annotations

import numpy as np

Segment = tuple[np.ndarray, np.ndarray]
Box = tuple[np.ndarray, np.ndarray]  # centre, half-sizes

EPS = 1e-9


def crossing(p: Segment, q: Segment) -> np.ndarray | None:
    """Where two segments cross (None if they do not, or only touch at an end)."""
    (a, b), (c, d) = p, q
    r, s = b - a, d - c
    denominator = r[0] * s[1] - r[1] * s[0]
    if abs(denominator) < EPS:
        return None  # parallel: bonds never lie along each other (they leave a box apart)
    t = ((c - a)[0] * s[1] - (c - a)[1] * s[0]) / denominator
    u = ((c - a)[0] * r[1] - (c - a)[1] * r[0]) / denominator
    if EPS < t < 1 - EPS and EPS < u < 1 - EPS:
        return a + t * r
    return None


def hits(segment: Segment, box: Box) -> bool:
    """Whether a segment passes through the inside of a box (Liang-Barsky clipping)."""
    (a, b), (centre, half) = segment, box
    low, high = centre - half, centre + half
    t0, t1 = 0.0, 1.0
    d = b - a
    for axis in range(2):
        if abs(d[axis]) < EPS:
            if not low[axis] < a[axis] < high[axis]:
                return False
            continue
        ta, tb = (low[axis] - a[axis]) / d[axis], (high[axis] - a[axis]) / d[axis]
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
        if t0 >= t1 - EPS:
            return False
    return True


def overlap(p: Box, q: Box) -> bool:
    """Whether two boxes overlap (touching is not overlapping)."""
    return bool(np.all(np.abs(p[0] - q[0]) < p[1] + q[1] - EPS))


def pieces(points: np.ndarray) -> list[Segment]:
    """A polyline's segments."""
    return list(zip(points[:-1], points[1:], strict=True))


def _bounds(segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return segments.min(axis=1), segments.max(axis=1)


class Obstacles:
    """What a picture holds so far, to place the next thing clear of it: boxes that
    nothing may enter, segments that no box may touch, and the ends of bonds (within
    `reach` of an end, where its stroke and half-arrow are) that no path may cross."""

    def __init__(self, boxes: list[Box] = (), reach: float = 0.0):
        self.boxes: list[Box] = list(boxes)
        self.segments: list[Segment] = []
        self.ticks: list[Segment] = []  # at a bond's end: no path crosses them
        self.ends: list[np.ndarray] = []
        self.reach = reach

    def add_boxes(self, boxes: list[Box]) -> None:
        self.boxes += boxes

    def add_bond(self, path: np.ndarray, ticks: list[Segment]) -> None:
        self.segments += pieces(path) + ticks
        self.ticks += ticks
        self.ends += [path[0], path[-1]]

    def add_path(self, points: np.ndarray) -> None:
        self.segments += pieces(points)

    def box_clear(self, box: Box) -> bool:
        """Whether `box` overlaps no box and no segment touches it."""
        if any_overlap(box, self.boxes):
            return False
        return not any(hits(s, box) for s in near(box, self.segments))

    def path_clear(self, points: np.ndarray) -> bool:
        """Whether a polyline enters no box, crosses no bond near its ends and runs along
        no segment."""
        for piece in pieces(points):
            if any(hits(piece, box) for box in near_boxes(piece, self.boxes)):
                return False
            around = (np.minimum(*piece) + np.maximum(*piece)) / 2, np.abs(piece[1] - piece[0]) / 2
            for segment in near(around, self.segments):
                at = crossing(piece, segment)
                if at is not None and (
                    any(segment is tick for tick in self.ticks)
                    or any(np.linalg.norm(at - end) < self.reach for end in self.ends)
                ):
                    return False
        return not along(points, self.segments)


def along(points: np.ndarray, segments: list[Segment], within: float = 0.04) -> bool:
    """Whether a polyline runs along a segment: two of its inner points within `within`."""
    if not segments or len(points) < 3:
        return False
    inner = points[1:-1]
    a, b = np.array([s[0] for s in segments]), np.array([s[1] for s in segments])
    d = b - a
    t = np.einsum("psk,sk->ps", inner[:, None] - a[None], d) / np.maximum(
        np.einsum("sk,sk->s", d, d), EPS
    )
    nearest = a[None] + np.clip(t, 0, 1)[..., None] * d[None]
    close = np.linalg.norm(inner[:, None] - nearest, axis=-1) < within
    return bool(np.any(close.sum(axis=0) >= 2))


def any_overlap(box: Box, boxes: list[Box]) -> bool:
    if not boxes:
        return False
    centres, halves = np.array([b[0] for b in boxes]), np.array([b[1] for b in boxes])
    return bool(np.any(np.all(np.abs(centres - box[0]) < halves + box[1] - EPS, axis=1)))


def near(box: Box, segments: list[Segment]) -> list[Segment]:
    """The segments whose bounding boxes meet `box`."""
    if not segments:
        return []
    low, high = _bounds(np.array(segments))
    close = np.all((low < box[0] + box[1]) & (high > box[0] - box[1]), axis=1)
    return [segments[i] for i in np.flatnonzero(close)]


def near_boxes(segment: Segment, boxes: list[Box]) -> list[Box]:
    """The boxes that meet `segment`'s bounding box."""
    if not boxes:
        return []
    centres, halves = np.array([b[0] for b in boxes]), np.array([b[1] for b in boxes])
    low, high = np.minimum(*segment), np.maximum(*segment)
    close = np.all((centres - halves < high) & (centres + halves > low), axis=1)
    return [boxes[i] for i in np.flatnonzero(close)]
