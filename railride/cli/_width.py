"""Rich tables that fit the width they are printed at (80 columns on a pipe or in a file).

Left alone, rich squeezes a table that is too wide by narrowing its widest columns, numbers
included, then cuts cells with an ellipsis and crops the lines at the console's width. A
`FitTable` narrows its columns only down to the longest word of each, so text wraps between
words and a number is never cut; a table that cannot fit that way is printed as several tables
over groups of its columns (`Split`), each repeating the columns that name the rows. Both decide
when printed, so the same table fits an 80-column terminal and a wider page (the HTML report)."""

from __future__ import annotations

import itertools
from typing import Callable, Generic, Sequence, TypeVar

from rich.measure import Measurement
from rich.table import Table
from rich.text import Text

T = TypeVar("T")

#: wide enough that rich measures every column at its natural (unwrapped) width
_UNLIMITED = 100_000


def _column_ranges(console, table: Table) -> list[tuple[int, int, bool]]:
    """(narrowest, natural, may wrap) of each column's content; the narrowest keeps every word
    whole (every cell, in a column that does not wrap)."""
    options = console.options.update_width(_UNLIMITED)
    ranges = []
    for column in table.columns:
        if column.width is not None:
            ranges.append((column.width, column.width, False))
            continue
        cells = [column.header, *column.cells] if table.show_header else list(column.cells)
        sizes = [Measurement.get(console, options, cell) for cell in cells] or [Measurement(1, 1)]
        natural = max(max(s.maximum for s in sizes), column.min_width or 0)
        narrowest = natural if column.no_wrap else max(max(s.minimum for s in sizes), column.min_width or 0)
        ranges.append((narrowest, natural, not column.no_wrap))
    return ranges


def _frame(console, table: Table, ranges) -> int:
    """What a table takes besides its columns' content: borders and padding."""
    measured = Measurement.get(console, console.options.update_width(_UNLIMITED), table)
    return measured.maximum - sum(hi for _, hi, _ in ranges)


def narrowest_width(console, table: Table) -> int:
    """The narrowest the table prints without cutting a word."""
    ranges = _column_ranges(console, table)
    return sum(lo for lo, _, _ in ranges) + _frame(console, table, ranges)


def _fitted_widths(console, table: Table, width: int) -> list:
    """The content width of each column (None: its natural width) for the table to fit
    ``width``: the widest columns that may wrap give first, each down to its longest word; the
    columns that name the rows (the first ``table.labels``) only when the others cannot give
    enough."""
    ranges = _column_ranges(console, table)
    labels = getattr(table, "labels", 1)
    room = width - _frame(console, table, ranges)
    if sum(hi for _, hi, _ in ranges) <= room:
        return [None] * len(ranges)

    def widths(cap: int, label_cap: int) -> list[int]:
        return [
            max(lo, min(hi, label_cap if i < labels else cap)) if wraps else hi
            for i, (lo, hi, wraps) in enumerate(ranges)
        ]

    cap = label_cap = max(hi for _, hi, _ in ranges)
    while cap > 1 and sum(widths(cap, label_cap)) > room:
        cap -= 1
    while label_cap > 1 and sum(widths(cap, label_cap)) > room:
        label_cap -= 1
    return [w if w < hi else None for w, (_, hi, _) in zip(widths(cap, label_cap), ranges)]


class FitTable(Table):
    """A rich Table that, when printed, fits the width it is given without cutting a word
    (as far as its longest words allow); its first ``labels`` columns name the rows and wrap
    last."""

    def __init__(self, *args, labels: int = 1, **kwargs):
        super().__init__(*args, **kwargs)
        self.labels = labels

    def __rich_console__(self, console, options):
        saved = [column.width for column in self.columns]
        fitted = _fitted_widths(console, self, options.max_width)
        try:
            for column, width in zip(self.columns, fitted):
                if width is not None:
                    column.width = width
            yield from super().__rich_console__(console, options)
        finally:  # the table stays as built: printed again, it fits again
            for column, width in zip(self.columns, saved):
                column.width = width


def fits(console, table: Table, width: int) -> bool:
    return narrowest_width(console, table) <= width


class Split(Generic[T]):
    """Tables ``build(group)`` over consecutive groups of ``items``, decided when printed: as few
    groups as fit the width, cut where ``breaks`` (indices into ``items``) allow if they can
    be, and where the parts come out most even (no part left with a lone column); each group
    is preceded by the ``repeat`` items (the reference every part compares against, such as the
    passive suspension). With more than one part the titles say "(part i of n)" and the caption
    comes once, under the last. ``build`` returns a `FitTable`."""

    def __init__(
        self,
        build: Callable[[list[T]], FitTable],
        items: Sequence[T],
        repeat: Sequence[T] = (),
        breaks: Sequence[int] = (),
    ):
        self.build = build
        self.items = list(items)
        self.repeat = list(repeat)
        self.breaks = set(breaks)

    def groups(self, console, width: int) -> list[list[T]]:
        n = len(self.items)
        if n < 2:
            return [self.items]
        # a column's width does not depend on the others: measure each item once
        base = narrowest_width(console, self.build(self.repeat))
        sizes = [narrowest_width(console, self.build([*self.repeat, item])) - base for item in self.items]

        def span(i: int, j: int) -> int:
            return base + sum(sizes[i:j])

        for parts in range(1, n + 1):
            ways = []
            for inner in itertools.combinations(range(1, n), parts - 1):
                cuts = [0, *inner, n]
                spans = [span(a, b) for a, b in zip(cuts, cuts[1:])]
                # a lone item too wide still gets a part of its own
                if all(w <= width or b - a == 1 for w, a, b in zip(spans, cuts, cuts[1:])):
                    # the widest part as narrow as can be, then the next widest, ...
                    ways.append((sum(c not in self.breaks for c in inner), sorted(spans, reverse=True), cuts))
            if ways:
                cuts = min(ways)[2]
                return [self.items[a:b] for a, b in zip(cuts, cuts[1:])]
        return [[item] for item in self.items]  # not reached: n parts of one item always do

    def tables(self, console, width: int) -> list[FitTable]:
        tables = [self.build([*self.repeat, *group]) for group in self.groups(console, width)]
        if len(tables) > 1:
            for i, table in enumerate(tables, start=1):
                table.title = f"{table.title or ''} (part {i} of {len(tables)})".strip()
                if i < len(tables):
                    table.caption = None  # said once, under the last part
        return tables

    def __rich_console__(self, console, options):
        for i, table in enumerate(self.tables(console, options.max_width)):
            if i:
                yield Text("")
            yield table
