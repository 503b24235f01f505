"""A bond graph as a picture: component labels, bonds with half-arrows, causal strokes.

`picture` places everything as plain data, in inches: the components where the layered
layout puts them (`layout`: left to right along the flow of power), each bond between the
boxes of its two labels with the half-arrow at its head (the direction of positive power)
and, once causality is assigned, the causal stroke across the end that receives the
effort; the bond numbers upright, beside their bond; the signals a modulated source reads
(e(X), f(X): no power, no bond) as dashed arrows from the component read. `problems` says
what in a picture overlaps or crosses where it must not, and `picture` keeps the first of
a few layouts that has nothing to say; `figure` draws the picture with matplotlib. A
part's ports (SS, in a subsystem's file drawn alone) are open ends, named in italics.
"""

from __future__ import annotations

import io
from dataclasses import replace
from functools import cache
from pathlib import Path
from types import MappingProxyType

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.patches import Circle, FancyArrowPatch, FancyBboxPatch
from matplotlib.path import Path as MplPath

from mtt.derivation.causality import CausalBondGraph
from mtt.files import write_atomic
from mtt.language.bondgraph import BondGraph
from mtt.language.components import Role
from mtt.present.geometry import Box, Obstacles, pieces
from mtt.present.layering import owner
from mtt.present.layout import BOX_PAD, BOX_TITLE, Variant, exit_distance, layout
from mtt.present.picture import END, TICK, BondPicture, Label, Picture, problems

__all__ = ["Picture", "figure", "picture", "problems", "render", "save", "signals"]

FONT, NUMBER_FONT, BOX_FONT, TITLE_FONT = 10.0, 7.0, 8.0, 9.0  # points
PAD = 0.15  # the white box behind a label, in font sizes
GAP = 0.05  # between a label's box and the bonds that end at it
PARALLEL = 0.12  # between bonds that join the same two components
MARGIN = 0.15  # around the picture
MAX_INCHES = 60.0  # a side of the figure: larger pictures are drawn smaller, fonts and all
VARIANTS = tuple(
    Variant(spacing, flip, turn)
    for spacing in (1.0, 1.7)
    for turn in (False, True)
    for flip in (False, True)
)
BENDS = (0.0, 0.3, -0.3, 0.6, -0.6, 1.0, -1.0)  # a signal's curvature, tried in turn
INK, NUMBER_INK, SIGNAL_INK, BOX_FILL = "#1a1a1a", "#7a7a7a", "#b04a1a", "#f3f3f3"
ROLE_INK = {Role.SOURCE: "#1f5fa8", Role.DETECTOR: "#1f5fa8", Role.PORT: NUMBER_INK}


@cache
def _measure(text: str, size: float, italic: bool) -> np.ndarray:
    """Half-sizes (inches) of a text's box as matplotlib draws it (line height at least
    that of "lp", as matplotlib lays out a line), with `PAD` around."""
    renderer, font = _renderer(), FontProperties(size=size, style="italic" if italic else None)
    width, height, _ = renderer.get_text_width_height_descent(text, font, ismath=False)
    _, line, _ = renderer.get_text_width_height_descent("lp", font, ismath=False)
    return (np.array([width, max(height, line)]) / 72 + 2 * PAD * size / 72) / 2


@cache
def _renderer() -> RendererAgg:
    return RendererAgg(1, 1, 72)  # 72 dpi: a pixel is a point


def _label_text(graph: BondGraph, name: str) -> str:
    """TYPE:NAME, the name as its subsystem's file writes it (the box gives the rest); a
    port by its name alone."""
    component = graph.component(name)
    inner = owner(graph, name)
    local = name[len(inner) + 1 :] if inner else name
    return local if component.type.role is Role.PORT else f"{component.type.name}:{local}"


def bond_picture(
    number: int, path: np.ndarray, half_a: np.ndarray, half_b: np.ndarray,
    stroke_at_head: bool | None, shift: float = 0.0,
) -> BondPicture:  # fmt: skip
    """The marks of a bond from a label centred at path[0] to one at path[-1] (boxes of
    half-sizes half_*, bends between), moved `shift` to its right (beside another bond
    between the same two labels). Its ends keep a causal stroke's length off the boxes."""
    path = np.array(path, dtype=float)
    out, back = _unit(path[1] - path[0]), _unit(path[-1] - path[-2])
    normal_out, normal = np.array([-out[1], out[0]]), np.array([-back[1], back[0]])
    path[0] = path[0] + out * _clearance(half_a, out) - normal_out * shift
    path[-1] = path[-1] - back * _clearance(half_b, -back) - normal * shift
    path[1:-1] -= normal * shift
    start, end = path[0], path[-1]
    barb = (end, end - back * TICK * 1.4 + normal * TICK)
    stroke = None
    if stroke_at_head is not None:
        at, across = (end, normal) if stroke_at_head else (start, normal_out)
        stroke = (at - across * TICK, at + across * TICK)
    return BondPicture(number, path, barb, stroke)


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector)


def _clearance(half: np.ndarray, direction: np.ndarray) -> float:
    """How far from a label's centre a bond leaving along `direction` starts: a gap off
    its box, and as far again as a stroke across the bond reaches along each axis."""
    across = np.abs([direction[1], direction[0]])
    return exit_distance(half + GAP + TICK * across, direction)


def picture(graph: BondGraph, causal: CausalBondGraph | None = None) -> Picture:
    """The picture of `graph` (with causal strokes when `causal` is given): the first of
    the layouts in `VARIANTS` with no problems, else the one with the fewest."""
    best = None
    for variant in VARIANTS:
        candidate = _place(graph, causal, variant)
        found = len(problems(candidate))
        if best is None or found < best[0]:
            best = (found, candidate)
        if not found:
            break
    return best[1]


def _place(graph: BondGraph, causal: CausalBondGraph | None, variant: Variant) -> Picture:
    ports = {c.name for c in graph.components if c.type.role is Role.PORT}
    texts = {c.name: _label_text(graph, c.name) for c in graph.components}
    size = {n: _measure(texts[n], FONT, n in ports) for n in texts}
    placed = layout(graph, {n: h + GAP + TICK for n, h in size.items()}, variant)
    position = placed.position
    labels = {
        c.name: Label(texts[c.name], position[c.name], size[c.name],
                      ROLE_INK.get(c.type.role, INK), c.name in ports)
        for c in graph.components
    }  # fmt: skip
    bonds = _bonds(graph, causal, labels, placed.bends)
    obstacles = Obstacles([label.box for label in labels.values()], reach=END)
    for bond in bonds:
        obstacles.add_bond(bond.path, [bond.barb] + ([bond.stroke] if bond.stroke else []))
    bonds = [replace(b, label=_number_box(b, obstacles)) for b in bonds]
    arrows = tuple(_signal(graph, reader, read, labels, bonds, obstacles)
                   for reader, read in signals(graph))  # fmt: skip
    boxes = subsystem_boxes(graph, position, {n: h + GAP for n, h in size.items()})
    box_names = {
        name: Label(name.rpartition(".")[2], np.array([lower[0], upper[1]]) + half * [1, -1]
                    + [0.03, -0.01], half, NUMBER_INK)  # in the top-left corner
        for name, (lower, upper) in boxes.items()
        for half in [_measure(name.rpartition(".")[2], BOX_FONT, False)]
    }  # fmt: skip
    corners = [(label.centre - label.half, label.centre + label.half) for label in labels.values()]
    corners += [(b.label[0] - b.label[1], b.label[0] + b.label[1]) for b in bonds]
    corners += [(b.path.min(axis=0), b.path.max(axis=0)) for b in bonds]
    corners += list(boxes.values()) + [(p.min(axis=0), p.max(axis=0)) for p in arrows]
    lower = np.min([c[0] for c in corners], axis=0) - MARGIN
    upper = np.max([c[1] for c in corners], axis=0) + MARGIN
    words = graph.name + (f": {graph.description}" if graph.description else "")
    half = _measure(words, TITLE_FONT, False)
    title = Label(
        words, np.array([lower[0] + MARGIN + half[0], upper[1] + half[1]]), half, NUMBER_INK
    )
    upper = np.array([max(upper[0], title.centre[0] + half[0] + MARGIN), upper[1] + 2 * half[1]])
    return Picture(title, MappingProxyType(labels), tuple(bonds), arrows,
                   MappingProxyType(boxes), MappingProxyType(box_names), lower,
                   upper)  # fmt: skip


def _bonds(graph: BondGraph, causal, labels: dict[str, Label], bends: dict) -> list[BondPicture]:
    """Each bond's line, barb and stroke; bonds between the same two labels side by side."""
    pairs: dict[frozenset, list[int]] = {}
    for bond in graph.bonds:
        pairs.setdefault(frozenset((bond.tail, bond.head)), []).append(bond.number)
    pictures = []
    for bond in graph.bonds:
        together = pairs[frozenset((bond.tail, bond.head))]
        shift = (together.index(bond.number) - (len(together) - 1) / 2) * PARALLEL
        tail, head = labels[bond.tail], labels[bond.head]
        via = bends.get((bond.tail, bond.head), np.empty((0, 2)))
        path = np.vstack([tail.centre, via, head.centre])
        at_head = None if causal is None else causal.stroke_at(bond.number) == bond.head
        pictures.append(bond_picture(bond.number, path, tail.half, head.half, at_head, shift))
    return pictures


def _number_box(bond: BondPicture, obstacles: Obstacles) -> Box:
    """The bond number's box: beside the middle of the bond's longest piece, on the side
    away from the barb, or failing room there, further along or on the other side."""
    half = _measure(str(bond.number), NUMBER_FONT, False)
    start, end = max(pieces(bond.path), key=lambda piece: np.linalg.norm(piece[1] - piece[0]))
    along = _unit(end - start)
    right = np.array([along[1], -along[0]])
    candidates = [
        (start + (end - start) * t + side * (exit_distance(half, side) + 0.02), half)
        for t in (0.5, 0.35, 0.65, 0.2, 0.8)
        for side in (right, -right)
    ]
    box = next((c for c in candidates if obstacles.box_clear(c)), candidates[0])
    obstacles.add_boxes([box])
    return box


def _signal(graph, reader: str, read: str, labels, bonds, obstacles: Obstacles) -> np.ndarray:
    """The arrow of a signal: the first curve from the component read to the source that
    touches no label, number or bond end; a port's signal starts at its bond's middle."""
    if read in labels:
        a, half_a = labels[read].centre, labels[read].half + GAP
    else:  # an SS port joined into a bond: the bond carries what the signal reads
        number = graph.port_bonds[read]
        path = next(b.path for b in bonds if b.number == number)
        a, half_a = path[len(path) // 2 - 1 : len(path) // 2 + 1].mean(axis=0), np.zeros(2)
    b, half_b = labels[reader].centre, labels[reader].half + GAP
    chord = b - a
    normal = np.array([-chord[1], chord[0]])
    candidates = []
    for bend in BENDS:
        control = (a + b) / 2 + bend * normal / 2
        out, back = control - a, control - b
        start = a + out / np.linalg.norm(out) * (exit_distance(half_a, out / np.linalg.norm(out))
                                                 if np.any(half_a) else 0.0)  # fmt: skip
        end = b + back / np.linalg.norm(back) * exit_distance(half_b, back / np.linalg.norm(back))
        t = np.linspace(0, 1, 17)[:, None]
        candidates.append((1 - t) ** 2 * start + 2 * t * (1 - t) * control + t**2 * end)
    path = next((c for c in candidates if obstacles.path_clear(c)), candidates[0])
    obstacles.add_path(path)
    return path


def subsystem_boxes(graph: BondGraph, position: dict, half: dict) -> dict[str, tuple]:
    """Each subsystem's box (lower-left, upper-right corners) around the labels of its
    components and the boxes of its own subsystems, with room for its name at the top."""
    boxes: dict[str, tuple] = {}
    for subsystem in sorted(graph.subsystems, key=lambda s: -s.name.count(".")):
        corners = [
            (position[name] - half[name], position[name] + half[name])
            for name in position
            if owner(graph, name) == subsystem.name
        ]
        corners += [
            box for inner, box in boxes.items() if inner.rpartition(".")[0] == subsystem.name
        ]
        if not corners:
            continue
        lower = np.min([c[0] for c in corners], axis=0) - BOX_PAD
        upper = np.max([c[1] for c in corners], axis=0) + BOX_PAD + np.array([0.0, BOX_TITLE])
        boxes[subsystem.name] = (lower, upper)
    return dict(sorted(boxes.items()))


def signals(graph: BondGraph) -> list[tuple[str, str]]:
    """(modulated source, component it reads) for every signal, once each."""
    pairs = []
    for component in graph.components:
        for use in getattr(component.argument, "signals", ()) or ():
            if (component.name, use.target) not in pairs:
                pairs.append((component.name, use.target))
    return pairs


def figure(graph: BondGraph, causal: CausalBondGraph | None = None) -> Figure:
    """The picture of `graph` drawn, with causal strokes when `causal` is given."""
    p = picture(graph, causal)
    width, height = p.upper - p.lower
    scale = min(1.0, MAX_INCHES / max(width, height))  # fonts and lines shrink with it
    fig = Figure(figsize=(width * scale, height * scale))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(p.lower[0], p.upper[0])
    ax.set_ylim(p.lower[1], p.upper[1])
    ax.set_aspect("equal")
    ax.axis("off")
    for name, (lower, upper) in p.boxes.items():
        ax.add_patch(FancyBboxPatch(lower, *(upper - lower), facecolor=BOX_FILL,
                                    boxstyle="round,pad=0,rounding_size=0.08", edgecolor=NUMBER_INK,
                                    linestyle=(0, (5, 3)), lw=0.9 * scale, zorder=0))  # fmt: skip
        _text(ax, p.box_names[name], BOX_FONT * scale, zorder=1)
    _text(ax, p.title, TITLE_FONT * scale)
    for label in p.labels.values():
        _text(ax, label, FONT * scale, zorder=3, boxed=True)
    marks = {"line": [b.path for b in p.bonds], "barb": [b.barb for b in p.bonds],
             "stroke": [b.stroke for b in p.bonds if b.stroke is not None]}  # fmt: skip
    for kind, segments in marks.items():
        width = {"line": 1.2, "barb": 1.2, "stroke": 1.6}[kind] * scale
        capstyle = "round" if kind == "barb" else "butt"
        ax.add_collection(LineCollection(segments, colors=INK, linewidths=width,
                                         capstyle=capstyle, label=kind))  # fmt: skip
    for bond in p.bonds:
        _text(ax, Label(str(bond.number), *bond.label, NUMBER_INK), NUMBER_FONT * scale)
    for bond in p.bonds:  # a port is an open end
        for end, name in zip(bond.ends, _ends(graph, bond.number), strict=True):
            if p.labels[name].port:
                ax.add_patch(Circle(end, 0.035, facecolor="white", edgecolor=INK,
                                    lw=1.0 * scale, zorder=4))  # fmt: skip
    for path in p.signals:
        ax.add_patch(FancyArrowPatch(path=MplPath(path), arrowstyle="-|>",
                                     mutation_scale=9 * scale, color=SIGNAL_INK,
                                     linestyle=(0, (4, 3)), lw=1.0 * scale, zorder=2))  # fmt: skip
    return fig


def _ends(graph: BondGraph, number: int) -> tuple[str, str]:
    bond = graph.bond(number)
    return bond.tail, bond.head


def _text(ax, label: Label, size: float, zorder: float = 2, boxed: bool = False) -> None:
    """A label's text, upright, centred in its box (a component's on white)."""
    box = {"boxstyle": f"square,pad={PAD}", "facecolor": "white", "edgecolor": "none"}
    ax.text(*label.centre, label.text, ha="center", va="center", fontsize=size,
            color=label.ink, style="italic" if label.port else "normal",
            bbox=box if boxed else None, zorder=zorder)  # fmt: skip


# Same model, same bytes: no dates, no random identifiers in the files.
_REPRODUCIBLE = {"svg": {"Date": None}, "pdf": {"CreationDate": None}, "png": {}}


def render(fig: Figure, format: str, dpi: float = 150) -> bytes:
    """The figure as svg, png or pdf bytes (`dpi`: the resolution of a png)."""
    buffer = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": "mtt", "svg.fonttype": "none"}):
        fig.savefig(buffer, format=format, dpi=dpi, metadata=_REPRODUCIBLE[format])
    return buffer.getvalue()


def save(fig: Figure, path: str | Path, dpi: float = 150) -> None:
    """Write a figure as the file's suffix says (.svg, .png or .pdf), atomically."""
    write_atomic(path, render(fig, Path(path).suffix.lstrip(".").lower(), dpi))
