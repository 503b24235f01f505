"""Hostile inputs of the kinds issue 22 found, as generators (used by
tests/test_fuzz_hostile.py with a fixed budget, and by tests/fuzz_campaign.py for as long
as you like): constant values that reach non-real numbers, huge exponents or deep nesting;
the values a generated module's functions are given; CSV files; a Tracker's timestamps;
filter texts. Each is drawn from a `random.Random`, so a failure reproduces from its seed.
"""

from __future__ import annotations

import random

FUNCTIONS = ["log", "sqrt", "exp", "sin", "cos", "tan", "tanh", "atan", "abs", "sign", "sat"]
LEAVES = ["3", "2", "1", "0.5", "-1", "-2", "pi", "1e300", "1e-300", "1e4000", "9" * 40]


def constant(rng: random.Random, depth: int) -> str:
    """A constant expression, often deep, with logarithms and roots of values that may be
    negative, fractional powers of negative bases and huge exponentials."""
    if depth <= 0 or rng.random() < 0.1:
        return rng.choice(LEAVES)
    inner = constant(rng, depth - 1)
    roll = rng.random()
    if roll < 0.45:
        return f"{rng.choice(FUNCTIONS)}({inner})"
    if roll < 0.6:
        return f"({inner})^({rng.choice(['1/2', '1/3', '0.5', '2', '-1', '3/4'])})"
    if roll < 0.7:
        return f"exp({rng.choice(['-', ''])}{rng.randint(0, 800)})"
    if roll < 0.85:
        return f"-{inner}"
    return f"({inner} {rng.choice('+-*/')} {constant(rng, depth // 2)})"


def constant_model(rng: random.Random) -> str:
    """An RC circuit whose resistance is a chain of parameters of hostile constants: the
    value literally, or through parameters naming the one before."""
    lines = ["model hostile"]
    chain = rng.random() < 0.4
    previous = rng.choice(LEAVES[:3])
    for i in range(rng.randint(1, 12) if chain else 1):
        value = (
            f"{rng.choice(FUNCTIONS)}({previous})" if chain else constant(rng, rng.randint(1, 60))
        )
        lines.append(f"param p{i} = {value}")
        previous = f"p{i}"
    lines += ["unknown c = 1", "Se:v -> 1:a", f"1:a -> R:r({previous})", "1:a -> C:c"]
    lines.append("1:a -> Df:y")
    return "\n".join(lines) + "\n"


def module_value(rng: random.Random):
    """A value a user might pass for k, k0, bounds, beta, S0 or C: right, wrong or huge."""
    return rng.choice([
        1.0, 0.1, -1.0, 0.0, 10**400, -(10**400), 1e308, -1e308, 1e149, 1e151, 5e-324,
        float("nan"), float("inf"), "1", "abc", None, [], [1.0], [1.0, 2.0, 3.0], (0, 10**400),
        (1.0, 0.5), {"c": 10**400}, {"x": 1}, complex(1, 1), True, [[1.0]], object(),
        "(1+s)^3", "(" * 400 + "1+s" + ")" * 400, "s^99", "1+s^1e9", "1/0",
    ])  # fmt: skip


CELLS = ["0", "1", "0.5", "-2e3", "1e400", "nan", "inf", "", " ", "x", '"1"', "1,2", "٣",
         "1_0", "\x00", "é", "0x1", "1e", "-", "1" * 300]  # fmt: skip


def csv_text(rng: random.Random) -> bytes:
    """A CSV file as a careless or hostile source writes it: odd headers, cells, extra or
    missing fields, blank lines, quotes, long lines, binary bytes, BOM, CRLF."""
    header = rng.choice(["t,u,y", "t,u,y,z", "t,y", "y,u,t", "t,u,u,y", "", "t;u;y", '"t",u,y'])
    lines = [header]
    for i in range(rng.randint(0, 12)):
        width = 3 + rng.choice([0, 0, 0, 1, -1, 5])
        cells = [rng.choice(CELLS) if rng.random() < 0.2 else repr(i * 0.1 + j)
                 for j in range(max(width, 0))]  # fmt: skip
        lines.append(",".join(cells))
        if rng.random() < 0.1:
            lines.append("")
    if rng.random() < 0.1:
        lines.insert(rng.randint(1, len(lines)), "1," * rng.choice([40_000, 5]) + "1")
    text = "\n".join(lines) + rng.choice(["\n", "", "\n\n"])
    if rng.random() < 0.1:
        text = text.replace("\n", "\r\n")
    data = text.encode("utf-8")
    if rng.random() < 0.1:
        data = b"\xef\xbb\xbf" + data
    if rng.random() < 0.05:
        at = rng.randint(0, len(data))
        data = data[:at] + bytes([rng.choice([0xFF, 0xFE, 0x80, 0x00])]) + data[at:]
    return data


def samples(rng: random.Random) -> list[tuple]:
    """A stream of (t, u, y) updates for a Tracker: mostly good samples and chunks, some bad
    (a time not after the last, huge, not finite, of another type, arrays of unequal
    length)."""
    t, out = 0.0, []
    for _ in range(rng.randint(3, 12)):
        roll = rng.random()
        if roll < 0.55:
            t += rng.choice([0.01, 0.01, 0.5, 1e-9])
            out.append((t, 1.0, rng.uniform(-1, 1)))
        elif roll < 0.7:
            times = [t + 0.01 * (i + 1) for i in range(rng.randint(1, 5))]
            t = times[-1]
            out.append((times, [1.0] * len(times), [0.1] * len(times)))
        else:
            bad = rng.choice([1e308, 1e200, 1e149, 1e16, t, t - 1, float("nan"), float("inf"),
                              -1e308, 10**400, "x", None])  # fmt: skip
            out.append(rng.choice([(bad, 1.0, 0.0), (t + 0.01, bad, 0.0), (t + 0.01, 1.0, bad),
                                   ([t + 0.01, bad], [1.0, 1.0], [0.0, 0.0]),
                                   ([t + 0.01], [1.0, 1.0], [0.0])]))  # fmt: skip
    return out


def filter_text(rng: random.Random) -> str:
    """C(s) as text: nested, long, odd tokens."""
    depth = rng.choice([0, 1, 5, 49, 50, 51, 300, 5000])
    core = rng.choice(["1+s", "(1+s)^4", "s", "2s+1", "1+s^30", "1e308*s+1", "1/0", "s s", "é"])
    return "(" * depth + core + ")" * (depth if rng.random() < 0.9 else depth - 1)
