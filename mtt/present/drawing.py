"""A bond graph as a picture: component labels, bonds with half-arrows, causal strokes.

The layout is networkx's (Kamada-Kawai: bonds of even length, few crossings; for large
models, where Kamada-Kawai takes seconds, a spring layout started from the layers of
distance to the input); matplotlib draws it.
Each bond runs between the boxes of its two labels, with the half-arrow at the head (the
direction of positive power) and, once causality is assigned, the causal stroke across
the end that receives the effort. The signals a modulated source reads (e(X), f(X): no
power, no bond) are dashed full arrows from the component read to the source.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import networkx as nx
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import FancyBboxPatch

from mtt.derivation.causality import CausalBondGraph
from mtt.estimator.codegen import write_atomic
from mtt.language.bondgraph import BondGraph
from mtt.language.components import Role

BOND_LENGTH = 1.0  # layout units between bonded labels
TICK = 0.09  # half-arrow barb and causal stroke, in layout units
GAP = 0.07  # between a label and the bonds that end at it
KAMADA_KAWAI_NODES = 150  # above, Kamada-Kawai takes seconds (20 s at 400 components)
MAX_INCHES = 60.0  # a side of the picture
CROSSING = 2.0  # the layout length of a bond into or out of a subsystem (others: 1)
BOX_PAD, BOX_FILL = 0.06, "#f3f3f3"  # a subsystem's box around its labels
INK, NUMBER_INK, SIGNAL_INK = "#1a1a1a", "#7a7a7a", "#b04a1a"
ROLE_INK = {Role.SOURCE: "#1f5fa8", Role.DETECTOR: "#1f5fa8", Role.JUNCTION: "#1a1a1a"}


def layout(graph: BondGraph) -> dict[str, np.ndarray]:
    """Positions of the components: laid out on the bonds, turned to lie wide."""
    simple = nx.Graph(graph.graph.to_undirected())
    if simple.number_of_nodes() == 1:
        return {next(iter(simple)): np.zeros(2)}
    for a, b, data in simple.edges(data=True):  # a bond across a subsystem's box is longer
        data["length"] = 1.0 if _owner(graph, a) == _owner(graph, b) else CROSSING
    if simple.number_of_nodes() <= KAMADA_KAWAI_NODES:
        position = nx.kamada_kawai_layout(simple, weight="length")
    else:  # the layers of distance from the input, relaxed: long chains meander, unknotted
        start = nx.bfs_layout(simple, start=graph.input) if nx.is_connected(simple) else None
        position = nx.spring_layout(simple, pos=start, seed=0, iterations=50)
    points = np.array(list(position.values()))
    points -= points.mean(axis=0)
    # principal axes: the longest extent of the drawing runs left to right
    _, _, axes = np.linalg.svd(points, full_matrices=False)
    points = points @ axes.T
    lengths = [np.linalg.norm(points[i] - points[j]) for i, j in _index_pairs(simple, position)]
    points *= BOND_LENGTH / (np.median(lengths) if lengths else 1.0)
    return dict(zip(position, points, strict=True))


def _owner(graph: BondGraph, name: str) -> str:
    """The innermost subsystem a component belongs to ("" for the model itself)."""
    owners = [s.name for s in graph.subsystems if name.startswith(s.name + ".")]
    return max(owners, key=len, default="")


def _index_pairs(simple: nx.Graph, position: dict) -> list[tuple[int, int]]:
    index = {name: i for i, name in enumerate(position)}
    return [(index[a], index[b]) for a, b in simple.edges()]


def _exit(half: np.ndarray, direction: np.ndarray) -> float:
    """How far from its centre along the unit `direction` a ray leaves a box of half-sizes
    `half` (a label's box, so that bonds start at the label's edge)."""
    scale = [h / abs(d) for h, d in zip(half, direction, strict=True) if abs(d) > 1e-12]
    return min(scale) if scale else 0.0


Segment = tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class BondPicture:
    """Where one bond's marks go, in layout units."""

    number: int
    line: Segment  # from the edge of the tail's label to the edge of the head's
    barb: Segment  # the half-arrow at the head, on the left of the direction of power
    stroke: Segment | None  # across the end that receives the effort (after causality)


def bond_picture(
    number: int, a: np.ndarray, b: np.ndarray, half_a: np.ndarray, half_b: np.ndarray,
    stroke_at_head: bool | None,
) -> BondPicture:  # fmt: skip
    """The marks of a bond from a label at `a` to one at `b` (boxes of half-sizes half_*)."""
    along = (b - a) / np.linalg.norm(b - a)
    normal = np.array([-along[1], along[0]])
    start = a + along * _exit(half_a, along)
    end = b - along * _exit(half_b, -along)
    barb = (end, end - along * TICK * 1.4 + normal * TICK)
    stroke = None
    if stroke_at_head is not None:
        at = end if stroke_at_head else start
        stroke = (at - normal * TICK, at + normal * TICK)
    return BondPicture(number, (start, end), barb, stroke)


def figure(graph: BondGraph, causal: CausalBondGraph | None = None) -> Figure:
    """The picture of `graph`, with causal strokes when `causal` is given."""
    position = layout(graph)
    points = np.array(list(position.values()))
    low, high = points.min(axis=0) - 0.6, points.max(axis=0) + 0.6
    width, height = high - low
    inches = min(1.35, MAX_INCHES / max(width, height))  # room for "GY:km" at 10 pt
    fig = Figure(figsize=(max(3.0, width * inches), max(2.0, height * inches)))
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_aspect("equal")
    ax.axis("off")
    labels = {}
    for component in graph.components:
        ink = ROLE_INK.get(component.type.role, INK)
        x, y = position[component.name]
        label = _local_label(graph, component.name)
        labels[component.name] = ax.text(
            x, y, label, ha="center", va="center", fontsize=10, color=ink,
            bbox={"boxstyle": "square,pad=0.15", "facecolor": "white", "edgecolor": "none"},
            zorder=3,
        )  # fmt: skip
    canvas.draw()  # the labels' sizes are known after a draw
    to_data = ax.transData.inverted()
    half = {}
    for name, text in labels.items():
        box = text.get_window_extent().transformed(to_data)
        half[name] = np.array([box.width, box.height]) / 2 + GAP
    for name, (lower, upper) in subsystem_boxes(graph, position, half).items():
        ax.add_patch(
            FancyBboxPatch(
                lower,
                *(upper - lower),
                boxstyle="round,pad=0,rounding_size=0.08",
                facecolor=BOX_FILL,
                edgecolor=NUMBER_INK,
                linestyle=(0, (5, 3)),
                lw=0.9,
                zorder=0,
            )
        )
        ax.text(lower[0] + 0.06, upper[1] - 0.05, name, ha="left", va="top", fontsize=8,
                color=NUMBER_INK, zorder=1)  # fmt: skip
    title = graph.name + (f": {graph.description}" if graph.description else "")
    ax.text(low[0] + 0.05, high[1] - 0.05, title, ha="left", va="top", fontsize=9,
            color=NUMBER_INK)  # fmt: skip
    for bond in graph.bonds:
        at_head = None if causal is None else causal.stroke_at(bond.number) == bond.head
        _draw(ax, bond_picture(bond.number, position[bond.tail], position[bond.head],
                               half[bond.tail], half[bond.head], at_head))  # fmt: skip
    for reader, read in signals(graph):
        start, end = bond_picture(0, position[read], position[reader], half[read],
                                  half[reader], None).line  # fmt: skip
        ax.annotate("", xy=end, xytext=start, arrowprops={
            "arrowstyle": "-|>", "linestyle": (0, (4, 3)), "color": SIGNAL_INK,
            "shrinkA": 0, "shrinkB": 0, "lw": 1.0, "connectionstyle": "arc3,rad=0.25"})  # fmt: skip
    return fig


def _local_label(graph: BondGraph, name: str) -> str:
    """TYPE:NAME, the name as its subsystem's file writes it (the box gives the rest)."""
    component = graph.component(name)
    owner = _owner(graph, name)
    return f"{component.type.name}:{name[len(owner) + 1 :] if owner else name}"


def subsystem_boxes(graph: BondGraph, position: dict, half: dict) -> dict[str, tuple]:
    """Each subsystem's box (lower-left, upper-right corners) around the labels of its
    components and the boxes of its own subsystems, with room for its name at the top."""
    boxes: dict[str, tuple] = {}
    for subsystem in sorted(graph.subsystems, key=lambda s: -s.name.count(".")):
        corners = [
            (position[name] - half[name], position[name] + half[name])
            for name in position
            if _owner(graph, name) == subsystem.name
        ]
        corners += [
            box for inner, box in boxes.items() if inner.rpartition(".")[0] == subsystem.name
        ]
        if not corners:
            continue
        lower = np.min([c[0] for c in corners], axis=0) - BOX_PAD
        upper = np.max([c[1] for c in corners], axis=0) + BOX_PAD + np.array([0.0, 0.16])
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


def _draw(ax, bond: BondPicture) -> None:
    (start, end) = bond.line
    ax.plot(*zip(*bond.line, strict=True), color=INK, lw=1.2, solid_capstyle="butt")
    ax.plot(*zip(*bond.barb, strict=True), color=INK, lw=1.2, solid_capstyle="round")
    if bond.stroke is not None:
        ax.plot(*zip(*bond.stroke, strict=True), color=INK, lw=1.6)
    along = (end - start) / np.linalg.norm(end - start)
    middle = (start + end) / 2 + np.array([along[1], -along[0]]) * 0.1  # away from the barb
    angle = math.degrees(math.atan2(along[1], along[0]))
    upright = angle - 180 * (abs(angle) > 90)
    ax.text(*middle, str(bond.number), fontsize=7, color=NUMBER_INK, ha="center", va="center",
            rotation=upright, rotation_mode="anchor")  # fmt: skip


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
