"""The drawing of a bond graph, checked as geometry: what `drawing.picture` places, on every
shipped model (and the test suite's subsystems), with the rules a textbook drawing keeps."""

from __future__ import annotations

import json
from dataclasses import replace
from functools import cache
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest
from matplotlib.collections import LineCollection
from matplotlib.patches import Circle, FancyArrowPatch

import mtt
from mtt.cli.main import main
from mtt.derivation.causality import assign
from mtt.derivation.pipeline import load
from mtt.language.components import Role
from mtt.present import drawing
from mtt.present.picture import BondPicture, problems, texts

ROOT = Path(__file__).resolve().parent.parent
SUBSYSTEMS = ROOT / "tests" / "data" / "subsystems"
PARTS = sorted((ROOT / "models" / "parts").glob("*.bg")) + sorted(
    (SUBSYSTEMS / "parts").glob("*.bg")
)
MODELS = sorted((ROOT / "models").glob("*.bg")) + sorted(SUBSYSTEMS.glob("*.bg")) + PARTS
IDS = [str(path.relative_to(ROOT)) for path in MODELS]


@cache
def drawn(path: Path):
    """A model with its causal strokes; a part (alone) without: they are its parent's."""
    graph = load(path, part=True)
    return graph, drawing.picture(graph, None if graph.open_ports else assign(graph))


def drawn_text(directory: Path, text: str) -> tuple:
    """A model written to `directory` and drawn with its causal strokes."""
    path = directory / "model.bg"
    path.write_text(text)
    graph = load(path)
    return graph, drawing.picture(graph, assign(graph))


def kinds(path: Path, *wanted: str) -> list[str]:
    return [str(p) for p in problems(drawn(path)[1]) if p.kind in wanted]


def test_every_shipped_model_is_checked():
    names = {path.stem for path in MODELS}
    assert {"rlc", "dc_drive", "absorber", "absorber_stages", "ladder", "plant"} <= names


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_no_bond_is_crossed_at_its_ends(path):
    """Where a bond's causal stroke and half-arrow are, nothing else passes."""
    assert kinds(path, "crossing_at_end") == []


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_labels_and_numbers_are_never_overlapped(path):
    """No text on another; no bond, stroke, barb or signal through a text; no signal along
    a bond; no component in a subsystem's box that is not part of it."""
    assert kinds(path, "overlap", "through", "along", "stranger") == []


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_everything_is_inside_the_picture(path):
    picture = drawn(path)[1]
    for what, (centre, half) in texts(picture):
        assert np.all(centre - half >= picture.lower) and np.all(centre + half <= picture.upper), (
            what
        )


def test_a_long_title_widens_a_small_picture(tmp_path):
    long = "a description longer than the bond graph " * 3
    _, picture = drawn_text(tmp_path, f'model small "{long}"\nSe:a -> De:b\n')
    centre, half = picture.title.box
    assert centre[0] + half[0] <= picture.upper[0] and centre[0] - half[0] > picture.lower[0]
    assert picture.upper[0] - picture.lower[0] > 2 * half[0]


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_bonds_do_not_cross(path):
    assert kinds(path, "crossing") == []


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_sources_left_detectors_right(path):
    graph, picture = drawn(path)
    x = {name: label.centre[0] for name, label in picture.labels.items()}
    if graph.input is not None:
        assert x[graph.input] == min(x.values())  # the input is leftmost
    for bond in graph.bonds:
        for end, other in ((bond.tail, bond.head), (bond.head, bond.tail)):
            role = graph.component(end).type.role
            # a part's ports: those its bonds leave on the left, those they reach on the right
            inward = role is Role.PORT and end == bond.tail
            if role is Role.SOURCE or inward:
                assert x[end] < x[other], f"{end} is not left of {other}"
            if role is Role.DETECTOR or role is Role.PORT and not inward:
                assert x[end] > x[other], f"{end} is not right of {other}"


@pytest.mark.parametrize("path", MODELS[:3], ids=IDS[:3])
def test_every_text_is_upright_and_inside_the_box_the_checks_use(path):
    """The checks above hold for the figure only if matplotlib draws each text inside the
    box the picture measured for it: rendered, each label's extent is within its box."""
    graph = load(path)
    fig = drawing.figure(graph, assign(graph))
    fig.canvas.draw()
    (ax,) = fig.axes
    assert all(text.get_rotation() == 0 for text in ax.texts)
    labels = drawing.picture(graph, assign(graph)).labels.values()
    boxes = {(label.text, *np.round(label.centre, 9)): label.box for label in labels}
    to_data = ax.transData.inverted()
    checked = 0
    for text in ax.texts:
        key = (text.get_text(), *np.round(text.get_position(), 9))
        if key in boxes:
            extent = text.get_window_extent().transformed(to_data)
            low, high = boxes[key][0] - boxes[key][1] - 0.01, boxes[key][0] + boxes[key][1] + 0.01
            assert low[0] <= extent.x0 and extent.x1 <= high[0], text.get_text()
            assert low[1] <= extent.y0 and extent.y1 <= high[1], text.get_text()
            checked += 1
    assert checked == len(graph.components)


def test_the_dc_drive_reads_as_the_papers_figure():
    """A level chain of junctions from the source to the load (the direction of power), the
    one-ports of each junction hung straight above and below it."""
    graph, picture = drawn(ROOT / "models" / "dc_drive.bg")
    at = {name: label.centre for name, label in picture.labels.items()}
    chain = ["v", "a", "km", "m", "s", "l", "jl"]
    assert [at[n][0] for n in chain] == sorted(at[n][0] for n in chain)
    assert np.ptp([at[n][1] for n in chain]) == pytest.approx(0, abs=1e-6)
    for element, junction in (("ra", "a"), ("ia", "a"), ("jm", "m"), ("cs", "s")):
        assert at[element][0] == pytest.approx(at[junction][0], abs=1e-6)
        assert abs(at[element][1] - at[junction][1]) > 0.3
    assert (at["ra"][1] - at["a"][1]) * (at["ia"][1] - at["a"][1]) < 0  # one above, one below


def test_the_problems_are_found():
    """The checks can fail: a label moved onto another, a bond that crosses another by its
    stroke, a signal along a bond are each reported."""
    graph, picture = drawn(ROOT / "models" / "rlc.bg")
    assert problems(picture) == []
    labels = dict(picture.labels)
    labels["r"] = replace(labels["r"], centre=labels["loop"].centre + [0.05, 0.0])
    moved = replace(picture, labels=labels)
    assert any(p.kind == "overlap" and "'R:r'" in p.what for p in problems(moved))
    first = picture.bonds[0]  # Se:v -> 1:loop, level
    start, end = first.ends
    across = np.array([[end[0] - 0.05, end[1] - 0.5], [end[0] - 0.05, end[1] + 0.5]])
    number = (across.mean(axis=0) + [0.3, 0], np.array([0.03, 0.05]))
    extra = BondPicture(99, across, (across[1], across[1] + [0.1, 0.1]), None, number)
    crossed = replace(picture, bonds=(*picture.bonds[1:], extra))
    found = [p for p in problems(crossed) if p.kind == "crossing_at_end"]
    assert found and "bond 99" in found[0].what
    along = replace(picture, signals=(np.linspace(start, end, 5),))
    assert [p.kind for p in problems(along)] == ["along"]


def test_a_bond_runs_between_labels_with_its_barb_at_the_head_and_stroke_where_effort_goes():
    a, b, half = np.array([0.0, 0.0]), np.array([2.0, 0.0]), np.array([0.3, 0.1])
    bond = drawing.bond_picture(7, np.array([a, b]), half, half, stroke_at_head=False)
    start, end = bond.ends
    clear = 0.3 + drawing.GAP
    np.testing.assert_allclose([start, end], [[clear, 0.0], [2 - clear, 0.0]])
    barb_from, barb_to = bond.barb
    np.testing.assert_allclose(barb_from, end)
    assert barb_to[0] < end[0] and barb_to[1] > 0  # back along the bond, on its left
    stroke = np.array(bond.stroke)
    np.testing.assert_allclose(stroke.mean(axis=0), start)  # across the tail's end
    assert stroke[0, 0] == stroke[1, 0]  # perpendicular to the bond
    assert drawing.bond_picture(7, np.array([a, b]), half, half, None).stroke is None
    # leaving a box at a slant, the stroke keeps off the box: its ends are outside it
    slant = drawing.bond_picture(1, np.array([a, [1.0, 1.0]]), half, half, stroke_at_head=False)
    for point in slant.stroke:
        assert np.any(np.abs(point) > half)


def test_the_figure_has_a_line_a_barb_and_a_stroke_per_bond():
    graph = load(mtt.example("dc_drive"))

    def segments(fig) -> dict[str, int]:
        (ax,) = fig.axes
        found = [c for c in ax.collections if isinstance(c, LineCollection)]
        return {c.get_label(): len(c.get_segments()) for c in found}

    assert segments(drawing.figure(graph, assign(graph))) == {"line": 11, "barb": 11, "stroke": 11}
    assert segments(drawing.figure(graph)) == {"line": 11, "barb": 11, "stroke": 0}


def test_signals_of_modulated_sources_are_drawn_as_dashed_arrows():
    graph = load(mtt.example("absorber"))  # MSf streams read the stage concentrations
    assert drawing.signals(graph) == [
        ("liquid1", "x1"), ("liquid2", "x2"), ("product", "x3"),
        ("gas3", "x3"), ("gas2", "x2"), ("off_gas", "x1"),
    ]  # fmt: skip
    (ax,) = drawing.figure(graph).axes
    arrows = [p for p in ax.patches if isinstance(p, FancyArrowPatch)]
    assert len(arrows) == 6
    picture = drawing.picture(graph)
    for (reader, read), path in zip(drawing.signals(graph), picture.signals, strict=True):
        # from the component read to the source: each end nearer its own label
        near = lambda point, name: np.linalg.norm(point - picture.labels[name].centre)  # noqa: E731
        assert near(path[0], read) < near(path[0], reader)
        assert near(path[-1], reader) < near(path[-1], read)


def test_subsystems_are_boxes_around_their_members_named_as_in_their_file():
    graph, picture = drawn(ROOT / "models" / "absorber_stages.bg")  # one stage file, thrice
    assert list(picture.boxes) == ["s1", "s2", "s3"]
    for name, (lower, upper) in picture.boxes.items():
        members = [n for n in picture.labels if n.startswith(name + ".")]
        assert len(members) == 6  # 0:x, C:h, 1:down, 1:up, MSf:liquid, MSf:gas
        for member in members:
            label = picture.labels[member]
            assert np.all(lower < label.centre - label.half)
            assert np.all(label.centre + label.half < upper)
    assert picture.labels["s2.x"].text == "0:x" and picture.labels["feed"].text == "Sf:feed"
    # the stages side by side, left to right, as the liquid flows
    spans = [(lower[0], upper[0]) for lower, upper in picture.boxes.values()]
    assert spans == sorted(spans) and all(a[1] < b[0] for a, b in pairwise(spans))
    svg = drawing.render(drawing.figure(graph), "svg").decode()
    assert ">s1</text>" in svg and ">MSf:liquid</text>" in svg


def test_bonds_between_the_same_two_components_are_drawn_apart(tmp_path):
    text = "model twice\nSe:a -> 0:n\n0:n -> 1:j\n0:n -> 1:j\n1:j -> De:v\n"
    _, picture = drawn_text(tmp_path, text)
    second, third = picture.bonds[1], picture.bonds[2]
    assert np.linalg.norm(second.path.mean(axis=0) - third.path.mean(axis=0)) > 0.1
    assert problems(picture) == []


def test_a_large_model_is_laid_out_in_one_row_clean_and_the_same_every_time():
    stages = 24
    lines = ["model ladder", "param r = 1", "param c = 1", "unknown k = 2", "Se:v -> 1:s1"]
    for i in range(1, stages + 1):
        lines += [f"1:s{i} -> R:r{i}(r)", f"1:s{i} -> 0:n{i}", f"0:n{i} -> C:c{i}(c)"]
        lines.append(f"0:n{i} -> 1:s{i + 1}" if i < stages else f"0:n{i} -> De:out")
    graph = mtt.load("\n".join(lines) + "\n").bondgraph
    first, again = drawing.picture(graph), drawing.picture(graph)
    assert problems(first) == []
    assert all(np.array_equal(first.labels[n].centre, again.labels[n].centre) for n in first.labels)
    chain = [first.labels[f"s{i}"].centre for i in range(1, stages + 1)]
    assert np.ptp([c[1] for c in chain]) == pytest.approx(0, abs=1e-6)
    width, height = drawing.figure(graph).get_size_inches()
    assert width <= drawing.MAX_INCHES and height < 3


@pytest.mark.parametrize("path", PARTS, ids=[str(p.relative_to(ROOT)) for p in PARTS])
def test_a_part_is_drawn_alone_with_its_ports_as_open_ends(path):
    graph, picture = drawn(path)
    assert graph.open_ports and graph.output is None
    for port in graph.open_ports:
        label = picture.labels[port]
        assert label.port and label.text == port.rpartition(".")[2]  # its name, no SS:
    assert all(bond.stroke is None for bond in picture.bonds)
    (ax,) = drawing.figure(graph).axes
    circles = [p for p in ax.patches if isinstance(p, Circle)]
    assert len(circles) == len(graph.open_ports)  # an open end at each port's bond
    ends = [end for bond in picture.bonds for end in bond.ends]
    for circle in circles:
        assert min(np.linalg.norm(np.array(circle.center) - end) for end in ends) < 1e-9


def test_mtt_check_and_draw_take_a_part_alone_and_derivation_does_not(tmp_path, capsys):
    part = str(ROOT / "models" / "parts" / "absorber_stage.bg")
    assert main(["check", part]) == 0
    out = capsys.readouterr().out
    assert "ok: part absorber_stage, 11 components, 10 bonds, ports liquid_in, gas_in" in out
    assert main(["check", "--json", part]) == 0
    (record,) = json.loads(capsys.readouterr().out)["files"]
    assert record["ok"] and record["input"] is None and record["ports"][-1] == "gas_out"
    assert main(["draw", part, "-o", str(tmp_path / "stage.svg")]) == 0
    assert "bond graph of part absorber_stage (ports liquid_in" in capsys.readouterr().out
    svg = (tmp_path / "stage.svg").read_text()
    assert ">liquid_in</text>" in svg and ">MSf:liquid</text>" in svg
    assert main(["tf", part]) == 2  # a transfer function needs a model
    assert "mtt check and mtt draw take a part alone" in capsys.readouterr().err


def test_a_causal_conflict_inside_a_part_is_found_by_check(tmp_path, capsys):
    part = tmp_path / "clash.bg"
    part.write_text("model clash\nSS:in -> 0:n\nSe:a -> 0:n\nSe:b -> 0:n\n0:n -> R:r(1)\n")
    assert main(["check", str(part)]) == 2
    assert "error[causal_conflict]" in capsys.readouterr().err


def test_a_bond_within_a_layer_is_moved_on_and_bonds_fan_out(tmp_path):
    # 1:b is one bond from 0:a directly and two through GY:g: laid out by distance alone,
    # GY:g and 1:b shared a layer and their bond ran through what hangs on 1:b
    graph, picture = drawn_text(
        tmp_path,
        "model triangle\nSe:u -> 0:a\n0:a -> 1:b\n0:a -> GY:g(2) -> 1:b\n"
        "1:b -> R:r(1)\n1:b -> C:c(1)\nMSe:m(2*e(a)) -> 1:b\n1:b -> Df:y\n",
    )
    assert problems(picture) == []
    x = {name: label.centre[0] for name, label in picture.labels.items()}
    assert x["u"] < x["a"] < x["g"] < x["b"] < x["y"]  # the two-port in the chain
    direct = next(
        b
        for b in picture.bonds
        if {graph.bond(b.number).tail, graph.bond(b.number).head} == {"a", "b"}
    )
    assert len(direct.path) == 3  # it passes GY's layer with a bend


def test_a_signal_that_reads_a_subsystems_port_starts_at_the_bond_it_became(tmp_path):
    (tmp_path / "stage.bg").write_text((SUBSYSTEMS / "parts" / "stage.bg").read_text())
    graph, picture = drawn_text(
        tmp_path,
        'model fed\nsubsystem s1 = "stage.bg"\nSe:v -> s1.in\ns1.out -> 1:j\n'
        "1:j -> R:r(1)\nMSe:m(2*e(s1.out)) -> 1:j\n1:j -> Df:y\n",
    )
    assert problems(picture) == []
    (arrow,) = picture.signals
    bond = next(b for b in picture.bonds if b.number == graph.port_bonds["s1.out"])
    assert np.linalg.norm(arrow[0] - bond.path.mean(axis=0)) < 1e-9  # from the joined bond


def test_a_piece_that_only_a_signal_reaches_follows_it_to_the_right(tmp_path):
    # two tanks: the lower is fed by a modulated source that reads the upper's outflow,
    # with no bond between them (issue 19's two_tanks has this shape)
    graph, picture = drawn_text(
        tmp_path,
        "model tanks\nSf:pump -> 0:h1\n0:h1 -> C:c1(1)\n0:h1 -> R:o1(1)\n"
        "MSf:fall(f(o1)) -> 0:h2\n0:h2 -> C:c2(1)\n0:h2 -> R:o2(1)\n0:h2 -> De:level\n",
    )
    assert problems(picture) == []
    x = {name: label.centre[0] for name, label in picture.labels.items()}
    assert x["pump"] < x["h1"] < x["o1"] < x["h2"] < x["level"]
