"""The rules a component's constitutive relations obey (`mtt check`): each gives one of the
two variables its component relates, once, in terms of the other (the component's own) and
of parameters; mtt/language/relations.py reads and inverts them."""

from __future__ import annotations

from mtt.language.diagnostics import Position


def relation_problems(label: str, name: str, kind, relations) -> list[tuple[str, Position]]:
    """What breaks the rules in the relations of the component `label` (named `name`, of
    the ComponentType `kind`, which relates two variables): each message and its place."""
    first, second = sorted(kind.relates)
    article = "an" if kind.summary[0] in "aeiou" else "a"
    relates = f"{article} {kind.summary} relates {first} and {second}"
    problems = []
    for index, relation in enumerate(relations):
        if relation.variable not in kind.relates:
            message = (
                f"{label}: a relation gives {first} or {second} ({relates}), "
                f"not {relation.variable!r}"
            )
            problems.append((message, relation.position))
            continue
        if any(r.variable == relation.variable for r in relations[:index]):
            message = (
                f"{label}: {relation.variable} is given twice; the second relation is the "
                "inverse of the first, so it gives the other variable"
            )
            problems.append((message, relation.position))
        for signal in relation.expression.signals:
            if signal.target != name:
                message = (
                    f"{label}: a relation is written in the component's own variables "
                    f"({first}, {second}) and parameters; {signal.text} is another "
                    "component's signal"
                )
            elif signal.kind not in kind.relates:
                message = (
                    f"{label}: {signal.kind} is not a variable of its relation ({relates}; "
                    "inside a relation e, f, q and p name those variables)"
                )
            elif signal.kind == relation.variable:
                message = (
                    f"{label}: {signal.kind} is on both sides of its relation; write it "
                    f"{relation.variable} = an expression of the other variable"
                )
            else:
                continue
            problems.append((message, signal.position))
    return problems
