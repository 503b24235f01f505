"""Sugiyama's first step for a bond graph: which elements hang on a junction, and the layer
of every other component.

Layers count the distance along the bonds from the input (for a part, from its inward
ports), so that a bond joins neighbouring layers; a bond within a layer has one end moved
on; other sources go one layer before what they drive, detectors one after what they
read; two subsystems never share a layer (a box holds no other subsystem's column); and a
bond that then passes layers gets a bend in each (Sugiyama's dummy nodes).
"""

from __future__ import annotations

from itertools import combinations

import networkx as nx

from mtt.language.bondgraph import BondGraph
from mtt.language.components import PortRule, Role

HUNG = {Role.RESISTOR, Role.STORAGE, Role.MODULATED}


def owner(graph: BondGraph, name: str) -> str:
    """The innermost subsystem a component belongs to ("" for the model itself)."""
    owners = [s.name for s in graph.subsystems if name.startswith(s.name + ".")]
    return max(owners, key=len, default="")


def owners(graph: BondGraph, name: str) -> tuple[str, ...]:
    """Every subsystem a component belongs to, outermost first."""
    return tuple(s.name for s in graph.subsystems if name.startswith(s.name + "."))


def inward_port(graph: BondGraph, name: str) -> bool:
    """A part's port whose bond points into the part (drawn on the left, like a source)."""
    return graph.component(name).type.role is Role.PORT and any(b.tail == name for b in graph.bonds)


def hung_elements(graph: BondGraph, simple: nx.Graph) -> dict[str, str]:
    """The elements hung on a junction (element -> junction): one-ports that store,
    dissipate or are modulated, of the junction's own file. A junction at the end of a
    chain continues it with its last element instead."""
    hung = {}
    for c in graph.components:
        if c.type.role in HUNG and c.type.ports is PortRule.ONE and simple.degree(c.name) == 1:
            (junction,) = simple[c.name]
            same_file = owner(graph, junction) == owner(graph, c.name)
            if graph.component(junction).type.role is Role.JUNCTION and same_file:
                hung[c.name] = junction
    for junction in dict.fromkeys(hung.values()):
        if sum(n not in hung for n in simple[junction]) <= 1:
            del hung[[h for h, j in hung.items() if j == junction][-1]]
    return hung


def layers(graph: BondGraph, spine: nx.Graph, hung: dict[str, str]) -> dict[str, int]:
    """Distance from the input along the bonds (a piece of the graph that only signals
    reach starts a layer after what they read), then the subsystems that share layers
    moved apart (a box holds no other subsystem's column); sources one layer before what
    they drive, detectors one after what they read."""
    role = {n: graph.component(n).type.role for n in spine}
    sources = [n for n in spine if role[n] is Role.SOURCE or inward_port(graph, n)]
    ends = {n for n in spine if spine.degree(n) == 1 and (n in sources or role[n] is Role.DETECTOR)}
    roots = [graph.input] if graph.input in sources else sources
    core = spine.subgraph(n for n in spine if n not in ends or n in roots)
    layer: dict[str, int] = {}
    starts = roots + [n for n in core if n not in roots]
    for part in sorted(nx.connected_components(core), key=lambda p: min(map(starts.index, p))):
        first = [n for n in starts if n in part]
        after = _signalled(graph, part, hung, layer)
        for depth, names in enumerate(
            nx.bfs_layers(core, [n for n in first if n in roots] or first[:1])
        ):
            layer.update(dict.fromkeys(names, depth + after))
    for again in (False, True):  # after moving subsystems apart, the model's own again
        for end in ends if not again else [e for e in ends if not owners(graph, e)]:
            (neighbour,) = spine[end]  # the input too: just before what it drives
            if neighbour in layer:
                layer[end] = layer[neighbour] + (-1 if end in sources else 1)
            else:  # a source bonded to a detector, alone
                layer[end] = int(end not in sources)
        if not again:
            two_ports = {n for n in core if role[n] is Role.TWO_PORT}
            _unflat(core, layer, two_ports)
            _apart(graph, layer)
            _unflat(core, layer, two_ports)
    low = min(layer.values())
    return {n: d - low for n, d in layer.items()}


def _signalled(graph: BondGraph, part: set, hung: dict[str, str], layer: dict) -> int:
    """The first layer for a piece of the graph: one after the last that its modulated
    sources read from the pieces already placed (0 when they read none)."""
    readers = [*part, *(h for h, junction in hung.items() if junction in part)]
    read = [
        hung.get(use.target, use.target)
        for reader in readers
        for use in getattr(graph.component(reader).argument, "signals", ()) or ()
    ]
    return max((layer[r] + 1 for r in read if r in layer and r not in part), default=0)


def _unflat(core: nx.Graph, layer: dict[str, int], two_ports: set) -> None:
    """No bond within a layer (it would run through the layer): one of its ends moves a
    layer on, the one whose move makes the fewest bonds pass a layer (then not a two-port,
    which stays between its two bonds; then the busier one, then the later in model
    order), until none is left."""
    order = {n: i for i, n in enumerate(core)}
    for _ in range(len(order) ** 2):
        flat = [(a, b) for a, b in core.edges() if layer[a] == layer[b]]
        if not flat:
            return

        def cost(name: str) -> tuple:
            passing = sum(layer[m] == layer[name] - 1 for m in core[name])
            return (passing, name in two_ports, -core.degree(name), -order[name])

        a, b = flat[0]
        layer[min((a, b), key=cost)] += 1


def _apart(graph: BondGraph, layer: dict[str, int]) -> None:
    """Move right whatever starts within another subsystem's layers, until no two
    subsystems (neither inside the other) share a layer."""
    members = {s.name: [n for n in layer if s.name in owners(graph, n)] for s in graph.subsystems}
    members = {s: m for s, m in members.items() if m}
    while True:
        span = {s: (min(layer[n] for n in m), max(layer[n] for n in m)) for s, m in members.items()}
        clashes = [
            (span[a], span[b], a, b) if span[a] <= span[b] else (span[b], span[a], b, a)
            for a, b in combinations(span, 2)
            if not (a.startswith(b + ".") or b.startswith(a + "."))
            and span[a][0] <= span[b][1]
            and span[b][0] <= span[a][1]
        ]
        if not clashes:
            return
        (_, high), (low, _), first, _ = min(clashes)
        keep = set(members[first])
        for name in layer:
            if layer[name] >= low and name not in keep:
                layer[name] += high - low + 1


def route(spine: nx.Graph, layer: dict[str, int], chains: dict) -> dict:
    """Bonds that pass layers get a bend in each (Sugiyama's dummy nodes), inside the
    boxes their ends are in where those boxes reach; (a, b) -> the bends from a to b."""
    routes = {}
    spans = {}
    for name, chain in chains.items():
        for box in chain:
            low, high = spans.get(box, (layer[name], layer[name]))
            spans[box] = (min(low, layer[name]), max(high, layer[name]))
    for a, b in list(spine.edges()):
        if abs(layer[a] - layer[b]) <= 1:
            continue
        if layer[a] > layer[b]:
            a, b = b, a
        spine.remove_edge(a, b)
        via = [f"\0{a}\0{b}\0{c}" for c in range(layer[a] + 1, layer[b])]
        for bend, c in zip(via, range(layer[a] + 1, layer[b]), strict=True):
            layer[bend] = c
            sides = [[s for s in chains[end] if spans[s][0] <= c <= spans[s][1]] for end in (a, b)]
            chains[bend] = tuple(max(sides, key=len))
        nx.add_path(spine, [a, *via, b])
        routes[(a, b)] = via
    return routes
