"""A readable, self-contained HTML report of tables, figures and text.

:func:`write_report` writes one HTML file with inline CSS; figures are
embedded as base64 PNG images, so the file can be mailed or archived without
any other asset. Text is escaped, never interpreted as HTML. Every table
and image fits a content column of :data:`CONTENT_WIDTH_PX` pixels: wide
tables are transposed, images scale down.

:func:`summarize` makes the summary a reader sees first: per run, one short
table of every method in plain words and units, the best value of each
column marked, and a sentence generated from the numbers.
:data:`GLOSSARY` explains every column once.

>>> import pathlib, tempfile
>>> import pandas as pd
>>> from matplotlib.figure import Figure
>>> figure = Figure()
>>> _ = figure.subplots().plot([0, 1], [0, 1])
>>> path = write_report(
...     pathlib.Path(tempfile.mkdtemp()) / "report.html",
...     title="Detection on PUMA 560",
...     sections=[
...         ("Summary", ["Nine collisions.", Table(pd.DataFrame({"x [N m]": [1.0]}), "One value")]),
...         ("Figures", Picture(figure, "a straight line from (0, 0) to (1, 1)")),
...     ],
... )
>>> "data:image/png;base64," in path.read_text(encoding="utf-8")
True
"""

from __future__ import annotations

from .html import (
    CONTENT_WIDTH_PX,
    WIDE_TABLE_COLUMNS,
    Glossary,
    Picture,
    ReportItem,
    Subheading,
    Table,
    write_report,
)
from .levels import level_counts_table, levels_section
from .summary import (
    GLOSSARY,
    STRONG_FORCE,
    ScenarioSummary,
    band_widths,
    best_cells,
    collision_table,
    summarize,
    summary_sentence,
)

__all__ = [
    "CONTENT_WIDTH_PX",
    "GLOSSARY",
    "STRONG_FORCE",
    "WIDE_TABLE_COLUMNS",
    "Glossary",
    "Picture",
    "ReportItem",
    "ScenarioSummary",
    "Subheading",
    "Table",
    "band_widths",
    "best_cells",
    "collision_table",
    "level_counts_table",
    "levels_section",
    "summarize",
    "summary_sentence",
    "write_report",
]
