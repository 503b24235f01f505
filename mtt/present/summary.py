"""A model at a glance: `mtt show`'s summary, and `mtt check`'s line and `--json` record of
a file."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mtt.language.bondgraph import summary_counts
from mtt.present.tables import rows as rows_text

if TYPE_CHECKING:
    from mtt.derivation.checking import Checked
    from mtt.language.bondgraph import BondGraph


def _argument(component) -> str:
    """A component's argument as shown: its constitutive relation when it is written as
    one (version 3), else its exact value."""
    if component.relation is not None:
        return component.relation.text()
    return "" if component.argument is None else str(component.argument.value)


def check_record(checked: Checked) -> dict:
    """The `check --json` record of one file (its shape is a public contract)."""
    file, parsed, graph, problem = checked.file, checked.parsed, checked.graph, checked.problem
    errors = problem.errors if problem else ()
    warnings = (problem.warnings if problem else ()) + (graph.warnings if graph else ())
    record = {
        "file": file,
        "ok": problem is None,
        "errors": [d.to_json() for d in errors],
        "warnings": [d.to_json() for d in warnings],
        "model": None, "components": 0, "bonds": 0, "parameters": {}, "unknown": [],
        "input": None, "output": None, "ports": [],
    }  # fmt: skip
    if parsed is not None:
        record["model"] = parsed.header.name if parsed.header else None
        record["components"] = len({use.name for use in parsed.mentions})
        record["bonds"] = len(parsed.bonds)
        record["parameters"] = {
            p.name: None if p.value is None else str(p.value) for p in parsed.parameters
        }
        record["unknown"] = [p.name for p in parsed.parameters if p.unknown]
    if graph is not None:
        record["components"] = len(graph.components)
        record["bonds"] = len(graph.bonds)
        record["parameters"] = {
            p.name: None if p.value is None else str(p.value) for p in graph.parameters.values()
        }
        # several inputs (outputs): TYPE:NAME separated by commas, as --input takes them
        record["input"] = ",".join(graph.component(n).label for n in graph.inputs) or None
        record["output"] = ",".join(graph.component(n).label for n in graph.outputs) or None
        record["ports"] = list(graph.open_ports)  # a part's own, checked alone
        record["unknown"] = list(graph.unknowns)
    record["warnings"] += [note.to_json() for note in checked.notes]
    return record


def check_text(graph: BondGraph, record: dict) -> str:
    """`mtt check`'s line for a valid file: what it is, its size, its ends and unknowns."""
    unknowns = graph.unknowns
    unknown = f", unknown{'s' * (len(unknowns) > 1)} {', '.join(unknowns)}" if unknowns else ""
    several = lambda names: "s" * (len(names) > 1)  # noqa: E731
    ends = (
        f"input{several(graph.inputs)} {signals_text(graph, graph.inputs)}, "
        f"output{several(graph.outputs)} {signals_text(graph, graph.outputs)}"
    )
    if graph.open_ports:
        ends = f"ports {', '.join(graph.open_ports)}"
    kind = "part" if graph.open_ports else "model"
    return (
        f"{record['file']}: ok: {kind} {graph.name}, {record['components']} components, "
        f"{record['bonds']} bonds, {ends}{unknown}"
    )


def signals_text(graph: BondGraph, names: tuple[str, ...]) -> str:
    """`Se:v`, or `Se:v and Se:tl`, `Df:a, Df:b and Df:c`."""
    labels = [graph.component(name).label for name in names] or ["none"]
    return " and ".join(filter(None, (", ".join(labels[:-1]), labels[-1])))


def describe(graph: BondGraph) -> str:
    """A readable summary of a bond graph, for `mtt show`."""
    lines = [f"model {graph.name}" + (f": {graph.description}" if graph.description else "")]
    lines.append(f"file {graph.source.name}")
    if graph.parameters:
        lines += ["", "parameters"]
        rows = []
        for p in graph.parameters.values():
            value = "(no value: symbolic)" if p.value is None else f"= {p.value.value}"
            role = "unknown" if p.name in graph.unknowns else "known"
            rows.append((p.name, value, role, p.description or ""))
        lines += rows_text(rows)
    counts = summary_counts(graph)
    lines += ["", f"components ({sum(counts.values())})"]
    rows = []
    for type_name in counts:
        members = [c for c in graph.components if c.type.name == type_name]
        names = ", ".join(c.name + (f"({_argument(c)})" if _argument(c) else "") for c in members)
        rows.append((type_name, members[0].type.summary, names))
    lines += rows_text(rows)
    lines += ["", f"bonds ({len(graph.bonds)}, tail -> head is the direction of positive power)"]
    rows = [
        (str(b.number), graph.component(b.tail).label, "->", graph.component(b.head).label)
        for b in graph.bonds
    ]
    lines += rows_text(rows)
    if graph.subsystems:
        lines += ["", f"subsystems ({len(graph.subsystems)})"]
        rows = []
        for sub in graph.subsystems:
            indent = "  " * sub.name.count(".")
            bindings = ", ".join(f"{name} = {value.value}" for name, value in sub.bindings)
            rows.append(
                (indent + sub.name.rpartition(".")[2], sub.file, bindings and f"({bindings})",
                 sub.description or "")
            )  # fmt: skip
        lines += rows_text(rows)
    lines += [
        "",
        f"input{'s' * (len(graph.inputs) > 1):3}{signals_text(graph, graph.inputs)}",
        f"output{'s' * (len(graph.outputs) > 1):2}{signals_text(graph, graph.outputs)}",
        f"unknown {', '.join(graph.unknowns) or '(none)'}",
    ]
    return "\n".join(lines)
