"""Where a bond graph's components go: in layers, left to right along the flow of power.

Textbooks draw a bond graph as a chain of junctions from the source on the left to the
detector on the right, with each junction's one-port elements hung above and below it.
This layout does that in Sugiyama's manner:

1. the spine (every component but the elements hung on a junction) is put in layers
   (`layering`: by distance from the input, subsystems apart, bends where bonds pass
   layers);
2. each layer is ordered by the barycentre of its neighbours in the layer before (then
   after), sweeping back and forth and keeping the order with the fewest crossings; the
   components of one subsystem stay together, so that its box holds no stranger;
3. the heights come from a linear programme (scipy's HiGHS): bonds as level as the order
   and the sizes of the labels allow, each subsystem's box clear of other components.

Distances are in inches at the drawing's natural size, from the labels' measured boxes.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations, pairwise

import networkx as nx
import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix

from mtt.language.bondgraph import BondGraph
from mtt.present.layering import hung_elements, layers, owners, route

SPAN = 0.42  # the visible length of a bond between layers
RISE = 0.32  # ... and of a bond to an element hung on its junction
VGAP = 0.26  # between the blocks of one layer
BOX_PAD, BOX_TITLE = 0.07, 0.17  # a subsystem's box around its labels; the strip for its name
BEND = 0.06  # how far labels keep from a bond that passes their layer
FAN = 0.16  # two bonds that leave one label part by this much where their strokes are
SWEEPS = 8  # barycentre sweeps (each down and up) while crossings remain
# the tilts from the vertical of 1, 2, 3... elements hung on one side of a junction
TILTS = {1: (0.0,), 2: (-32.0, 32.0), 3: (-50.0, 0.0, 50.0)}


@dataclass(frozen=True)
class Variant:
    """A way to lay a graph out: the drawing tries a few until one is clean."""

    spacing: float = 1.0  # scales the gaps between layers and between blocks
    flip: bool = False  # hang the first element on the other side
    turn: bool = False  # turn hung elements away from the junction's other bonds


def exit_distance(half: np.ndarray, direction: np.ndarray) -> float:
    """How far from its centre along the unit `direction` a ray leaves a box of half-sizes
    `half` (a label's box: bonds start at its edge)."""
    scale = [h / abs(d) for h, d in zip(half, direction, strict=True) if abs(d) > 1e-12]
    return min(scale) if scale else 0.0


@dataclass(frozen=True)
class Layout:
    """The centre of every component's label, and the bends of bonds that pass layers."""

    position: dict[str, np.ndarray]
    bends: dict[tuple[str, str], np.ndarray]  # (a, b) -> the points between a and b, in order


def layout(graph: BondGraph, half: dict[str, np.ndarray], variant: Variant = Variant()) -> Layout:
    """Where the labels go (inches, y up) for labels of half-sizes `half`."""
    simple = nx.Graph(graph.graph.to_undirected())
    hung = hung_elements(graph, simple)
    spine = nx.Graph(simple.subgraph(n for n in simple if n not in hung))
    layer = layers(graph, spine, hung)
    chains = {n: owners(graph, n) for n in spine}
    routes = route(spine, layer, chains)
    half = {**half, **{d: np.array([0.0, BEND]) for via in routes.values() for d in via}}
    columns = _order(spine, layer, chains)
    x = None
    away: dict[str, list[float]] = {}  # a junction's spine bonds' angles, once known
    for _ in range(1 + variant.turn):  # hang, place; then hang clear of the bonds, again
        offsets: dict[str, dict[str, np.ndarray]] = {}
        for column in columns:
            for i, name in enumerate(column):
                elements = [h for h, j in hung.items() if j == name]
                up_first = (i <= (len(column) - 1) / 2) != variant.flip
                offsets[name] = _hang(name, elements, half, up_first, away.get(name, []))
        extent = {n: _extent(n, offsets[n], half) for column in columns for n in column}
        x = _abscissae(columns, extent, chains, variant.spacing)
        fans = _fans(spine, columns, x, half, variant.spacing)
        y = _ordinates(spine, columns, extent, chains, variant.spacing, fans)
        position = {n: np.array([x[c], y[n]]) for c, column in enumerate(columns) for n in column}
        away = {
            n: [np.degrees(np.arctan2(*(position[m] - position[n])[::-1])) for m in spine[n]]
            for n in position
        }
    for name, placed in offsets.items():
        for element, offset in placed.items():
            position[element] = position[name] + offset
    bends = {}
    for (a, b), via in routes.items():
        bends[(a, b)] = np.array([position[d] for d in via])
        bends[(b, a)] = bends[(a, b)][::-1]
    return Layout({c.name: position[c.name] for c in graph.components}, bends)


def _order(spine: nx.Graph, layer: dict[str, int], chains: dict) -> list[list[str]]:
    """The layers, each ordered top to bottom: barycentre sweeps, the fewest crossings."""
    columns: list[list[str]] = [[] for _ in range(max(layer.values()) + 1)]
    for name in layer:
        columns[layer[name]].append(name)
    best, fewest = [list(c) for c in columns], _crossings(columns, spine)
    for _ in range(SWEEPS):
        if fewest == 0:
            break
        for step in (1, -1):
            indices = range(1, len(columns)) if step == 1 else range(len(columns) - 2, -1, -1)
            for c in indices:
                rank = {n: i for i, n in enumerate(columns[c - step])}
                here = {n: i for i, n in enumerate(columns[c])}

                def barycentre(name: str, rank=rank, here=here) -> float:
                    ranks = [rank[m] for m in spine[name] if m in rank]
                    return float(np.mean(ranks)) if ranks else float(here[name])

                columns[c] = _grouped(columns[c], barycentre, chains)
            crossings = _crossings(columns, spine)
            if crossings < fewest:
                best, fewest = [list(c) for c in columns], crossings
    return best


def _grouped(names: list[str], key, chains: dict, depth: int = 0) -> list[str]:
    """`names` sorted by `key`, each subsystem's members together (ordered by their mean)."""
    groups: dict[str, list[str]] = {}
    for name in names:
        groups.setdefault(chains[name][depth] if len(chains[name]) > depth else name, []).append(
            name
        )
    ordered = sorted(groups.items(), key=lambda item: np.mean([key(n) for n in item[1]]))
    result = []
    for label, members in ordered:
        inner = label not in members  # a subsystem: order its members within it
        result += _grouped(members, key, chains, depth + 1) if inner else members
    return result


def _crossings(columns: list[list[str]], spine: nx.Graph) -> int:
    total = 0
    for left, right in pairwise(columns):
        at = {n: i for i, n in enumerate(right)}
        edges = [(i, at[m]) for i, n in enumerate(left) for m in spine[n] if m in at]
        total += sum((a - c) * (b - d) < 0 for (a, b), (c, d) in combinations(edges, 2))
    return total


def _hang(junction: str, elements: list[str], half: dict, up_first: bool, away: list) -> dict:
    """Each hung element's offset from its junction: alternately above and below, fanned
    out when several share a side (as far from the junction's other bonds, at angles
    `away`, as `TILTS` allows), each at a bond's length from the junction's box."""
    sides = ([], [])
    for i, element in enumerate(elements):
        sides[i % 2].append(element)
    offsets = {}
    for sign, members in zip((1, -1) if up_first else (-1, 1), sides, strict=True):
        tilts = _tilts(len(members), [sign * (90 - a) for a in away])
        for element, tilt in zip(members, tilts, strict=False):
            direction = np.array([np.sin(np.radians(tilt)), sign * np.cos(np.radians(tilt))])
            reach = exit_distance(half[junction], direction) + RISE
            reach += exit_distance(half[element], direction)
            offsets[element] = direction * reach * (1 + 0.25 * (len(members) > 1))
    return offsets


def _tilts(count: int, others: list[float]) -> tuple[float, ...]:
    """`count` tilts from the vertical (degrees), the fan of `TILTS` turned as far from
    the `others` (the tilts of the junction's bonds) as it can turn, up to 30 degrees."""
    fan = np.array(TILTS.get(count, np.linspace(-60.0, 60.0, count)))

    def clearance(turn: float) -> float:
        gaps = [abs((t + turn) - o) for t in fan for o in others if abs(o) <= 90]
        return min([*gaps, 45.0])  # beyond 45 degrees, any is as good

    turns = sorted(np.arange(-30.0, 31.0, 5.0), key=abs)  # the least turn among the best
    return tuple(fan + max(turns, key=clearance))


@dataclass(frozen=True)
class Extent:
    """How far a block (a spine component and its hung elements) reaches from its centre."""

    up: float
    down: float
    left: float
    right: float


def _extent(name: str, offsets: dict, half: dict) -> Extent:
    boxes = [(np.zeros(2), half[name])] + [(o, half[e]) for e, o in offsets.items()]
    return Extent(
        up=max(o[1] + h[1] for o, h in boxes),
        down=max(h[1] - o[1] for o, h in boxes),
        left=max(h[0] - o[0] for o, h in boxes),
        right=max(o[0] + h[0] for o, h in boxes),
    )


def _abscissae(columns, extent: dict, chains: dict, spacing: float) -> list[float]:
    """Each layer's x: the widest blocks of two layers a bond apart, plus room for the
    edges of the subsystems' boxes between them."""
    spans: dict[str, tuple[int, int]] = {}
    for c, column in enumerate(columns):
        for name in column:
            for box in chains[name]:
                low, high = spans.get(box, (c, c))
                spans[box] = (min(low, c), max(high, c))
    x = [0.0]
    for c in range(1, len(columns)):
        edges = sum((low <= c - 1 <= high) != (low <= c <= high) for low, high in spans.values())
        gap = SPAN * spacing + 2 * BOX_PAD * edges
        right = max(extent[n].right for n in columns[c - 1])
        x.append(x[-1] + right + gap + max(extent[n].left for n in columns[c]))
    return x


def _fans(spine: nx.Graph, columns, x: list[float], half: dict, spacing: float) -> dict:
    """The least height between neighbours in a layer that are bonded to one label in the
    next (or last) layer: the angle between the two bonds there must keep each one's
    causal stroke, `FAN` from the label's centre, off the other."""
    least = {}
    for c, column in enumerate(columns):
        for a, b in pairwise(column):
            for shared in set(spine[a]) & set(spine[b]):
                reach = half[shared][0]  # the box, its gap and a stroke's length: inches
                if reach <= FAN * spacing:  # a bend: no stroke there
                    continue
                angle = np.arcsin(FAN * spacing / reach)
                dx = abs(
                    x[c] - x[c + 1 if shared in columns[min(c + 1, len(columns) - 1)] else c - 1]
                )
                least[(a, b)] = max(least.get((a, b), 0.0), float(dx * np.tan(angle)))
    return least


def _ordinates(
    spine: nx.Graph, columns, extent: dict, chains: dict, spacing: float, fans: dict
) -> dict:
    """Heights: the least total slope of the bonds between blocks, with each layer in its
    order and every subsystem's box clear of the blocks outside it (a linear programme)."""
    names = [n for column in columns for n in column]
    index = {n: i for i, n in enumerate(names)}
    edges = list(spine.edges())
    inside = {n: set(chains[n]) for n in names}
    top, bottom = len(names) + len(edges), len(names) + len(edges) + 1
    rows: list[tuple[dict[int, float], float]] = []  # sum(coefficient * variable) <= bound
    for e, (a, b) in enumerate(edges):  # t_e >= |y_a - y_b|
        t = len(names) + e
        rows += [
            ({index[a]: 1, index[b]: -1, t: -1}, 0.0),
            ({index[b]: 1, index[a]: -1, t: -1}, 0.0),
        ]
    for above, below in _separated(columns, chains):
        gap = extent[above].down + extent[below].up + VGAP * spacing
        gap += BOX_PAD * len(inside[above] - inside[below])
        gap += (BOX_PAD + BOX_TITLE) * len(inside[below] - inside[above])
        gap = max(gap, fans.get((above, below), 0.0))
        rows.append(({index[below]: 1, index[above]: -1}, -gap))
    for n in names:
        rows.append(({index[n]: 1, top: -1}, -extent[n].up))
        rows.append(({bottom: 1, index[n]: -1}, -extent[n].down))
    values = [v for row, _ in rows for v in row.values()]
    at = ([r for r, (row, _) in enumerate(rows) for _ in row], [k for row, _ in rows for k in row])
    matrix = coo_matrix((values, at), shape=(len(rows), bottom + 1)).tocsr()
    cost = np.zeros(bottom + 1)
    for e, (a, b) in enumerate(edges):  # chains level first, and most inside a box
        chain = min(spine.degree(a), spine.degree(b)) > 1
        cost[len(names) + e] = (1 + chain) * (1 + len(inside[a] & inside[b]))
    cost[top], cost[bottom] = 0.05, -0.05  # then as compact as that allows
    bounds = [(None, None)] * (top + 1) + [(0.0, 0.0)]
    result = linprog(cost, A_ub=matrix, b_ub=[b for _, b in rows], bounds=bounds, method="highs")
    if not result.success:  # cannot happen: the constraints stack blocks, always feasible
        raise RuntimeError(f"layout: {result.message}")
    return {n: float(result.x[index[n]]) for n in names}


def _separated(columns, chains: dict) -> list[tuple[str, str]]:
    """(above, below) pairs that must not overlap: neighbours in a layer, and a subsystem's
    members against every other block in the layers its box spans."""
    pairs = [(a, b) for column in columns for a, b in pairwise(column)]
    rank = {n: (i + 0.5) / len(column) for column in columns for i, n in enumerate(column)}
    layer = {n: c for c, column in enumerate(columns) for n in column}
    for box in dict.fromkeys(s for chain in chains.values() for s in chain):
        members = [n for n in layer if box in chains[n]]
        span = range(min(layer[m] for m in members), max(layer[m] for m in members) + 1)
        mean = float(np.mean([rank[m] for m in members]))
        for c in span:
            column = columns[c]
            inside = [i for i, n in enumerate(column) if box in chains[n]]
            for i, name in enumerate(column):
                if box in chains[name]:
                    continue
                above = i < inside[0] if inside else rank[name] < mean
                pairs += [(name, m) if above else (m, name) for m in members]
    return pairs
