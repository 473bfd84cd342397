"""The HTML writer: items (tables, figures, text) in sections, one self-contained file."""

from __future__ import annotations

import base64
import html
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..exceptions import InputTypeError, InputValueError

__all__ = ["Glossary", "Picture", "ReportItem", "Subheading", "Table", "write_report"]

CONTENT_WIDTH_PX = 1100
"""Width of the content column [px]; every table and image fits inside it."""

WIDE_TABLE_COLUMNS = 9
"""A table with more columns than this (index included) is shown transposed when it has
fewer rows than columns, and split into parts of fewer columns otherwise."""


@dataclass(frozen=True)
class Table:
    """A titled table of the report.

    Attributes
    ----------
    frame : DataFrame
        The values, already in the units of the column names; floats are
        shown with ``digits`` significant digits, NaN as "–".
    title : str
        Caption above the table.
    note : str
        Sentence below the table (e.g. what the bold cells mean).
    best : frozenset of (row label, column label)
        Cells shown in bold as the best of their column.
    digits : int
        Significant digits of floats.
    """

    frame: pd.DataFrame
    title: str
    note: str = ""
    best: frozenset[tuple[Any, Any]] = field(default_factory=frozenset)
    digits: int = 3


@dataclass(frozen=True)
class Picture:
    """A figure with its alternative text (what it shows, for who cannot see it)."""

    figure: Figure
    alt: str


@dataclass(frozen=True)
class Subheading:
    """A heading inside a section."""

    text: str


@dataclass(frozen=True)
class Glossary:
    """Terms and their explanations, as a definition list."""

    entries: Mapping[str, str]


ReportItem = pd.DataFrame | pd.Series | Figure | str | Table | Picture | Subheading | Glossary

_CSS = f"""
* {{ box-sizing: border-box; }}
body {{ font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       max-width: {CONTENT_WIDTH_PX}px; margin: 2rem auto; padding: 0 1.5rem; color: #222;
       line-height: 1.5; }}
main {{ max-width: 100%; }}
h1 {{ border-bottom: 2px solid #444; padding-bottom: .3rem; }}
h2 {{ margin-top: 2.5rem; border-bottom: 1px solid #bbb; padding-bottom: .2rem; }}
h3 {{ margin-top: 1.8rem; }}
p {{ max-width: 48rem; }}
p.lead {{ font-size: 1.1rem; background: #f3f6fa; border-left: 4px solid #3b6ea5;
          padding: .5rem .8rem; max-width: none; }}
table {{ border-collapse: collapse; margin: .3rem 0 0 0; font-size: .9rem;
        font-variant-numeric: tabular-nums; max-width: 100%; }}
caption {{ caption-side: top; text-align: left; font-weight: 600; padding: .3rem 0; }}
th, td {{ border: 1px solid #ccc; padding: .25rem .6rem; text-align: right; }}
thead th {{ background: #f0f0f0; }}
tbody th {{ text-align: left; background: #fafafa; }}
td.best {{ font-weight: 700; background: #e3f1e3; }}
.table-wrap {{ overflow-x: auto; max-width: 100%; margin: 1rem 0; }}
.note {{ font-size: .85rem; color: #555; margin: .2rem 0 0 0; }}
figure {{ margin: 1rem 0; max-width: 100%; }}
img {{ max-width: 100%; height: auto; display: block; }}
dl {{ display: grid; grid-template-columns: max-content 1fr; gap: .3rem 1rem; }}
dt {{ font-weight: 600; }}
dd {{ margin: 0; }}
footer {{ margin-top: 3rem; color: #555; font-size: .85rem; border-top: 1px solid #ccc; }}
footer code {{ word-break: break-all; }}
"""


def _format_cell(value: Any, digits: int) -> str:
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        return f"{value:.{digits}g}" if abs(value) < 10**digits else f"{value:.0f}"
    if value is None or (not isinstance(value, str | tuple) and pd.isna(value)):
        return "–"
    if isinstance(value, tuple):
        return ", ".join(str(v) for v in value)
    return str(value)


def _label(value: Any) -> str:
    return " · ".join(str(v) for v in value) if isinstance(value, tuple) else str(value)


def _render_table(table: Table) -> str:
    """A table; transposed when wide with few rows, split into parts when still too wide."""
    frame = table.frame
    best = table.best
    if frame.shape[1] + 1 > WIDE_TABLE_COLUMNS and frame.shape[0] < frame.shape[1]:
        frame = frame.T
        best = frozenset((column, row) for row, column in table.best)
    per_part = WIDE_TABLE_COLUMNS - 1
    if frame.shape[1] <= per_part:
        return _render_part(table, frame, best, table.title)
    n_parts = -(-frame.shape[1] // per_part)
    return "\n".join(
        _render_part(
            table,
            frame.iloc[:, k * per_part : (k + 1) * per_part],
            best,
            f"{table.title} (part {k + 1} of {n_parts})",
        )
        for k in range(n_parts)
    )


def _render_part(table: Table, frame: pd.DataFrame, best: frozenset[Any], title: str) -> str:
    head_index = html.escape(_label(frame.index.name or ""))
    header = "".join(f"<th>{html.escape(_label(c))}</th>" for c in frame.columns)
    rows = []
    for label, values in zip(frame.index, frame.itertuples(index=False), strict=True):
        cells = []
        for column, value in zip(frame.columns, values, strict=True):
            mark = ' class="best"' if (label, column) in best else ""
            cells.append(f"<td{mark}>{html.escape(_format_cell(value, table.digits))}</td>")
        rows.append(f"<tr><th>{html.escape(_label(label))}</th>\n" + "\n".join(cells) + "</tr>")
    caption = f"<caption>{html.escape(title)}</caption>" if title else ""
    note = f'\n<p class="note">{html.escape(table.note)}</p>' if table.note else ""
    return (
        f'<div class="table-wrap">\n<table>{caption}\n<thead><tr><th>{head_index}</th>{header}'
        f"</tr></thead>\n<tbody>\n" + "\n".join(rows) + f"\n</tbody>\n</table>{note}\n</div>"
    )


def _render_figure(picture: Picture, dpi: float) -> str:
    buffer = io.BytesIO()
    picture.figure.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    encoded = base64.b64encode(buffer.getvalue()).decode("ascii")
    alt = html.escape(picture.alt or "figure", quote=True)
    return f'<figure><img src="data:image/png;base64,{encoded}" alt="{alt}"></figure>'


def _render_text(text: str) -> str:
    paragraphs = [block.strip() for block in text.split("\n\n") if block.strip()]
    return "\n".join(f"<p>{html.escape(block)}</p>" for block in paragraphs)


def _render_item(item: Any, where: str, dpi: float) -> str:
    if isinstance(item, pd.Series):
        item = item.to_frame()
    if isinstance(item, pd.DataFrame):
        return _render_table(Table(item, str(item.attrs.get("title", "")), digits=4))
    if isinstance(item, Table):
        return _render_table(item)
    if isinstance(item, Figure):
        return _render_figure(Picture(item, item.get_suptitle() or "figure"), dpi)
    if isinstance(item, Picture):
        return _render_figure(item, dpi)
    if isinstance(item, Subheading):
        return f"<h3>{html.escape(item.text)}</h3>"
    if isinstance(item, Glossary):
        entries = "\n".join(
            f"<dt>{html.escape(term)}</dt><dd>{html.escape(text)}</dd>"
            for term, text in item.entries.items()
        )
        return f"<dl>\n{entries}\n</dl>"
    if isinstance(item, str):
        return _render_text(item)
    raise InputTypeError(
        f"{where} must be a pandas DataFrame or Series, a matplotlib Figure, a str, or a "
        f"Table, Picture, Subheading or Glossary of sensorless.report; got {type(item).__name__}"
    )


def _section_items(items: Any) -> list[Any]:
    """A section's items: one item or a list/tuple of items."""
    if isinstance(items, list | tuple):
        return list(items)
    return [items]


def _footer(provenance: Mapping[str, str] | None) -> str:
    if not provenance:
        return "<footer>Written by sensorless.</footer>"
    lines = "\n".join(
        f"<dt>{html.escape(str(key))}</dt><dd><code>{html.escape(str(value))}</code></dd>"
        for key, value in provenance.items()
    )
    return f"<footer>\n<p>Written by sensorless.</p>\n<dl>\n{lines}\n</dl>\n</footer>"


def write_report(
    path: str | Path,
    *,
    title: str,
    sections: Sequence[tuple[str, ReportItem | Sequence[ReportItem]]],
    dpi: float = 100.0,
    provenance: Mapping[str, str] | None = None,
) -> Path:
    """Write a self-contained HTML report.

    Parameters
    ----------
    path : str or Path
        Destination file (its directory must exist); overwritten.
    title : str
        Title of the page and of its first heading.
    sections : sequence of (str, items)
        Headings with their content, in order. ``items`` is one item or a
        list of items, each a :class:`Table` (a titled table, best cells in
        bold; with more than :data:`WIDE_TABLE_COLUMNS` columns it is shown
        transposed if it has fewer rows than columns, else split into parts), a
        pandas DataFrame or Series (a table titled by ``frame.attrs["title"]``
        if set, floats with 4 significant digits, missing values as "–"), a
        :class:`Picture` or a matplotlib Figure (an embedded PNG whose
        alternative text is the Picture's ``alt`` or the figure's title), a
        :class:`Subheading`, a :class:`Glossary` or a str (paragraphs
        separated by blank lines, HTML-escaped).
    dpi : float
        Resolution of the embedded figures [dots per inch].
    provenance : mapping of str to str, optional
        What makes the report reproducible (library version, seeds, command
        line), shown in the footer.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputValueError
        A section is not a ``(heading, items)`` pair, or ``dpi`` is not positive.
    TypeError
        An item is not of a type listed above.
    """
    if not isinstance(dpi, int | float) or isinstance(dpi, bool) or not dpi > 0:
        raise InputValueError(f"dpi must be a positive number; got {dpi!r}")
    body: list[str] = [f"<h1>{html.escape(str(title))}</h1>"]
    for index, section in enumerate(sections):
        if not isinstance(section, tuple | list) or len(section) != 2:
            raise InputValueError(
                f"sections[{index}] must be a pair (heading, items); got {section!r:.80}"
            )
        heading, items = section
        body.append(f"<section>\n<h2>{html.escape(str(heading))}</h2>")
        for k, item in enumerate(_section_items(items)):
            body.append(_render_item(item, f"sections[{index}] item {k}", float(dpi)))
        body.append("</section>")
    page = "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en">',
            "<head>",
            '<meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{html.escape(str(title))}</title>",
            f"<style>{_CSS}</style>",
            "</head>",
            "<body>",
            "<main>",
            *body,
            "</main>",
            _footer(provenance),
            "</body>",
            "</html>",
            "",
        ]
    )
    destination = Path(path)
    destination.write_text(page, encoding="utf-8")
    return destination
