"""A readable, self-contained HTML report of tables, figures and text.

:func:`write_report` writes one HTML file with inline CSS; figures are
embedded as base64 PNG images, so the file can be mailed or archived without
any other asset. Text is escaped, never interpreted as HTML.

>>> import pathlib, tempfile
>>> import pandas as pd
>>> from matplotlib.figure import Figure
>>> figure = Figure()
>>> _ = figure.subplots().plot([0, 1], [0, 1])
>>> path = write_report(
...     pathlib.Path(tempfile.mkdtemp()) / "report.html",
...     title="Detection on PUMA 560",
...     sections=[("Summary", ["Nine collisions.", pd.DataFrame({"x": [1.0]}), figure])],
... )
>>> "data:image/png;base64," in path.read_text(encoding="utf-8")
True
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from .exceptions import InputTypeError, InputValueError

__all__ = ["write_report"]

ReportItem = pd.DataFrame | pd.Series | Figure | str

_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       max-width: 72rem; margin: 2rem auto; padding: 0 1.5rem; color: #222;
       line-height: 1.5; }
h1 { border-bottom: 2px solid #444; padding-bottom: .3rem; }
h2 { margin-top: 2.5rem; border-bottom: 1px solid #bbb; padding-bottom: .2rem; }
p { max-width: 48rem; }
table { border-collapse: collapse; margin: 1rem 0; font-size: .9rem;
        font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #ccc; padding: .25rem .6rem; text-align: right; }
th { background: #f0f0f0; }
tbody tr:nth-child(even) { background: #fafafa; }
.table-wrap { overflow-x: auto; }
figure { margin: 1rem 0; }
img { max-width: 100%; height: auto; }
footer { margin-top: 3rem; color: #777; font-size: .8rem; }
"""


def _format_float(value: float) -> str:
    return f"{value:.4g}"


def _render_table(table: pd.DataFrame | pd.Series) -> str:
    frame = table.to_frame() if isinstance(table, pd.Series) else table
    rendered = frame.to_html(border=0, float_format=_format_float, na_rep="–", escape=True)
    return f'<div class="table-wrap">\n{rendered}\n</div>'


def _render_figure(figure: Figure, dpi: float) -> str:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    encoded = base64.b64encode(buffer.getvalue()).decode("ascii")
    alt = html.escape(figure.get_suptitle() or "figure", quote=True)
    return f'<figure><img src="data:image/png;base64,{encoded}" alt="{alt}"></figure>'


def _render_text(text: str) -> str:
    paragraphs = [block.strip() for block in text.split("\n\n") if block.strip()]
    return "\n".join(f"<p>{html.escape(block)}</p>" for block in paragraphs)


def _render_item(item: Any, where: str, dpi: float) -> str:
    if isinstance(item, pd.DataFrame | pd.Series):
        return _render_table(item)
    if isinstance(item, Figure):
        return _render_figure(item, dpi)
    if isinstance(item, str):
        return _render_text(item)
    raise InputTypeError(
        f"{where} must be a pandas DataFrame or Series, a matplotlib Figure or a str; "
        f"got {type(item).__name__}"
    )


def _section_items(items: Any) -> list[Any]:
    """A section's items: one item or a list/tuple of items."""
    if isinstance(items, list | tuple):
        return list(items)
    return [items]


def write_report(
    path: str | Path,
    *,
    title: str,
    sections: Sequence[tuple[str, ReportItem | Sequence[ReportItem]]],
    dpi: float = 100.0,
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
        list of items, each a pandas DataFrame or Series (an HTML table,
        floats with 4 significant digits, missing values as "–"), a
        matplotlib Figure (an embedded PNG) or a str (paragraphs separated by
        blank lines, HTML-escaped).
    dpi : float
        Resolution of the embedded figures [dots per inch].

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputValueError
        A section is not a ``(heading, items)`` pair, or ``dpi`` is not positive.
    TypeError
        An item is not a DataFrame, Series, Figure or str.
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
            *body,
            "<footer>Written by sensorless.</footer>",
            "</body>",
            "</html>",
            "",
        ]
    )
    destination = Path(path)
    destination.write_text(page, encoding="utf-8")
    return destination
