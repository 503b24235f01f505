"""A drawn bond graph as data (inches, y up), and what must never happen on it.

The rules a textbook drawing keeps: no two texts overlap (labels, bond numbers, subsystem
names, the title); no bond, half-arrow, causal stroke or signal arrow runs through a text;
nothing crosses a bond at its ends, where its stroke and half-arrow are; no component sits
in a subsystem's box that it is not part of. `problems` lists every breach, computed from
the positions, so that the drawing can choose a clean layout and tests can check one.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from mtt.present.geometry import Box, Segment, along, crossing, hits, pieces

TICK = 0.1  # the half-arrow's barb and half a causal stroke
END = 2.5 * TICK  # the end of a bond that holds its stroke and half-arrow


@dataclass(frozen=True)
class Label:
    """A text on the picture: a component's name, in a box that bonds end at."""

    text: str
    centre: np.ndarray
    half: np.ndarray  # half-sizes of the text's box
    ink: str
    port: bool = False  # a part's port: an open end, named in italics

    @property
    def box(self) -> Box:
        return (self.centre, self.half)


@dataclass(frozen=True)
class BondPicture:
    """Where one bond's marks go."""

    number: int
    path: np.ndarray  # from the edge of the tail's label to the edge of the head's, bends between
    barb: Segment  # the half-arrow at the head, on the left of the direction of power
    stroke: Segment | None  # across the end that receives the effort (after causality)
    label: Box | None = None  # the number's box, upright, beside the line

    @property
    def ends(self) -> tuple[np.ndarray, np.ndarray]:
        return self.path[0], self.path[-1]


@dataclass(frozen=True)
class Picture:
    title: Label
    labels: MappingProxyType  # component name -> Label
    bonds: tuple[BondPicture, ...]
    signals: tuple[np.ndarray, ...]  # polylines, from the component read to the source
    boxes: MappingProxyType  # subsystem -> (lower-left, upper-right)
    box_names: MappingProxyType  # subsystem -> the Label of its name, in its box's corner
    lower: np.ndarray  # the picture's corners
    upper: np.ndarray


@dataclass(frozen=True)
class Problem:
    kind: str  # overlap, through, along, crossing_at_end, crossing, stranger
    what: str

    def __str__(self) -> str:
        return f"{self.kind}: {self.what}"


def _pairs(low_a, high_a, low_b, high_b) -> np.ndarray:
    """Index pairs (i, j) of rectangles a[i], b[j] (corner arrays) that meet."""
    if not len(low_a) or not len(low_b):
        return np.empty((0, 2), dtype=int)
    meet = (low_a[:, None] < high_b[None]) & (high_a[:, None] > low_b[None])
    return np.argwhere(meet.all(axis=-1))


def _corners(segments: list[Segment]) -> tuple[np.ndarray, np.ndarray]:
    array = np.array(segments).reshape(-1, 2, 2)
    return array.min(axis=1), array.max(axis=1)


def texts(p: Picture) -> list[tuple[str, Box]]:
    """Every text on the picture and its box."""
    found = [(f"label {label.text!r} ({name})", label.box) for name, label in p.labels.items()]
    found += [(f"the number of bond {b.number}", b.label) for b in p.bonds]
    found += [(f"the name of subsystem {s}", label.box) for s, label in p.box_names.items()]
    return found + [("the title", p.title.box)]


def marks(p: Picture) -> list[tuple[str, Segment, str, int | None, tuple]]:
    """Every stroke of ink but the boxes: (what, segment, kind, the bond it belongs to, the
    bond's ends it holds); kind is line, tick (a half-arrow or a causal stroke, at a bond's
    end) or signal."""
    found = []
    for b in p.bonds:
        n, last = b.number, len(b.path) - 2
        for k, piece in enumerate(pieces(b.path)):
            ends = tuple(
                point for point, end in zip(piece, (k == 0, k == last), strict=True) if end
            )
            found.append((f"bond {n}", piece, "line", n, ends))
        found.append((f"the half-arrow of bond {n}", b.barb, "tick", n, ()))
        if b.stroke is not None:
            found.append((f"the causal stroke of bond {n}", b.stroke, "tick", n, ()))
    for k, path in enumerate(p.signals, start=1):
        found += [(f"signal arrow {k}", piece, "signal", None, ()) for piece in pieces(path)]
    return found


def problems(p: Picture) -> list[Problem]:
    """Every breach of the rules above."""
    found: list[Problem] = []
    boxes = texts(p)
    low = np.array([c - h for _, (c, h) in boxes])
    high = np.array([c + h for _, (c, h) in boxes])
    for i, j in _pairs(low, high, low, high):
        if i < j:
            found.append(Problem("overlap", f"{boxes[i][0]} overlaps {boxes[j][0]}"))
    ink = marks(p)
    seg_low, seg_high = _corners([m[1] for m in ink])
    for i, j in _pairs(seg_low, seg_high, low, high):
        if hits(ink[i][1], boxes[j][1]):
            found.append(Problem("through", f"{ink[i][0]} runs through {boxes[j][0]}"))
    lines = [m[1] for m in ink if m[2] != "signal"]
    for k, path in enumerate(p.signals, start=1):
        if along(path, lines):
            found.append(Problem("along", f"signal arrow {k} runs along a bond"))
    for i, j in _pairs(seg_low, seg_high, seg_low, seg_high):
        kind = _crossing_kind(ink[i], ink[j]) if i < j else None
        if kind is not None:
            found.append(Problem(kind, f"{ink[i][0]} crosses {ink[j][0]}"))
    for name, (lower, upper) in p.boxes.items():
        for other, label in p.labels.items():
            inside = other.startswith(name + ".")
            if (
                not inside
                and np.all(label.centre + label.half > lower)
                and np.all(label.centre - label.half < upper)
            ):
                found.append(Problem("stranger", f"{other} is in the box of subsystem {name}"))
    return found


def _crossing_kind(a: tuple, b: tuple) -> str | None:
    """How two marks cross: at a bond's end (where its stroke and half-arrow are), in the
    middle of two bonds, or acceptably (a signal over the middle of a bond, or over a
    signal); None when they do not cross."""
    (_, one, kind_a, bond_a, ends_a), (_, other, kind_b, bond_b, ends_b) = a, b
    if bond_a == bond_b and bond_a is not None or kind_a == kind_b == "signal":
        return None
    at = crossing(one, other)
    if at is None:
        return None
    if "tick" in (kind_a, kind_b):
        return "crossing_at_end"
    if any(np.linalg.norm(at - end) < END for end in ends_a + ends_b):
        return "crossing_at_end"
    return "crossing" if kind_a == kind_b == "line" else None
