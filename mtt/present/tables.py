"""Tables as people and spreadsheets read them: aligned text columns, and CSV."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence


def rows(table: Sequence[Sequence[str]], indent: str = "  ") -> list[str]:
    """The rows of `table` (cells as text, the first row a header or not) as lines whose
    columns line up."""
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    return [
        (indent + "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True))).rstrip()
        for row in table
    ]


def csv_text(header: Sequence[str], table: Iterable[Sequence[object]]) -> str:
    """A CSV file's text: the header, then a line per row (numbers as Python prints them)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(table)
    return buffer.getvalue()
