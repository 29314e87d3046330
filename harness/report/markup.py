"""HTML building blocks shared by every page of the report (``index.html``, the bench and
stress pages, ``compare.html``): the style sheet, a page's head, tables, figures and the small
Markdown the harness writes, and the sections folded in ``<details>``. Pages are
self-contained: inline CSS, and one small inline script, which opens every folded section
while the page prints."""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence
from pathlib import Path

from harness.report.views import FIGURES, escape_html

CSS = """
body{font-family:-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:0 auto;max-width:1280px;
padding:0 18px 40px;color:#222;line-height:1.45}
h1{font-size:1.7em;margin:.6em 0 .2em}
h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.6em}
h3{margin:1.4em 0 .3em} .lead{font-size:1.04em;max-width:62em}
.facts{color:#555;font-size:.92em} .facts b{color:#222}
table{border-collapse:collapse;font-size:.8em;margin:.4em 0 .8em}
th,td{border:1px solid #ddd;padding:2px 6px;text-align:right;white-space:nowrap}
th{background:#f4f4f4} td.l,th.l,th.wrap{text-align:left}
tr.engine td{background:#fbfbf6} tr.flag td{background:#fff1f0}
img{max-width:100%;height:auto} figure{margin:.6em 0} figcaption{font-size:.85em;color:#555}
.pair{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
.pair img.diagram{width:380px;max-width:100%}
.fail{color:#b00;font-weight:bold} .pass{color:#070} .muted{color:#777}
nav.contents{font-size:.9em;background:#f8f8f8;border:1px solid #e4e4e4;padding:6px 12px;
margin:.8em 0} nav.contents ol{margin:.2em 0;padding-left:1.4em}
nav.contents ol.scenarios{columns:3;font-size:.92em} code{background:#f4f4f4;padding:0 3px}
details{margin:.3em 0 .8em} summary{cursor:pointer;color:#335}
.scroll{overflow-x:auto;max-width:100%}
.pair{flex-wrap:wrap;gap:10px} .pair>div{flex:0 1 auto;min-width:0}
.pair>figure{flex:0 0 auto;margin:0}
td.note,th.note{white-space:normal;min-width:11em;max-width:22em;text-align:left}
td.wrap{white-space:normal;text-align:left;overflow-wrap:anywhere;max-width:70em}
p.notes{font-size:.8em;color:#733;margin:-.4em 0 .8em;max-width:60em}
.why dt{font-weight:bold;margin-top:.6em} .why dd{margin:.2em 0 .2em 1.2em;max-width:62em}
.override{color:#a40;font-weight:bold} .back{font-size:.85em}
nav.contents ol.groups{columns:4;font-size:.92em} nav.contents ol.groups ol{columns:1}
details.group>summary{font-size:1.1em;margin:.4em 0}
span.heat{display:block;margin:-2px -6px;padding:2px 6px}
span.heat.flagged{background-image:repeating-linear-gradient(135deg,
 rgba(90,90,90,.45) 0 1px,transparent 1px 6px)}
details.fold>summary{margin-top:1.2em;border-bottom:1px solid #ddd;padding-bottom:.2em}
summary>h2,summary>h3{display:inline;border:0;margin:0;padding:0}
details.scenario>summary{margin-top:.5em;border-bottom:1px solid #eee}
summary .headline{color:#555;font-size:.9em;margin-left:.6em}
.folded{scroll-margin-top:4em}
@media print{
body{max-width:none;padding:0;font-size:10pt}
nav.contents,.back,summary::marker{display:none}
details::details-content{content-visibility:visible;display:block}
summary{list-style:none;color:#222}
figure,table,tr,.pair,summary{break-inside:avoid}
summary,h2,h3,h4{break-after:avoid}
.scroll{overflow:visible} table{font-size:7pt} th,td{white-space:normal;padding:1px 3px}
.pair{display:block} img{width:auto;max-width:100%;height:auto}
figure img{width:100%} figure img.diagram{width:60%}
a{color:inherit;text-decoration:none}
}
"""

#: Printing shows every folded section: CSS alone cannot open a ``<details>`` (the print
#: style sheet reveals their content where the browser supports ``::details-content``), so
#: this opens the closed ones before printing and closes them again after.
PRINT_SCRIPT = """<script>
(function () {
  var opened = [];
  window.addEventListener('beforeprint', function () {
    document.querySelectorAll('details:not([open])').forEach(function (d) {
      d.open = true; opened.push(d);
    });
  });
  window.addEventListener('afterprint', function () {
    opened.forEach(function (d) { d.open = false; });
    opened = [];
  });
})();
</script>"""


PAGE_HEAD = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
             "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
             "<title>{title}</title><style>{css}</style>{script}</head><body>")


def page_head(title: str) -> str:
    return PAGE_HEAD.format(title=escape_html(title), css=CSS, script=PRINT_SCRIPT)


def folded(anchor: str, title: str, body: str, headline: str = "", level: int = 2,
           unfolded: bool = False, css_class: str = "fold") -> str:
    """A section folded in a ``<details>``: its summary says the section's ``title`` (a
    heading of ``level``) and its ``headline`` (HTML: the counts a reader decides by),
    ``body`` (HTML) unfolds below; ``unfolded``: shown unfolded when the page opens.

    The ``anchor`` id is on the body's wrapper, inside the folded content: a link to it
    opens the section (browsers open the closed ``<details>`` around a fragment's target,
    nested ones too), where an id on the ``<details>`` itself would scroll to a closed one.
    """
    summary = f"<h{level}>{escape_html(title)}</h{level}>" + (
        f" <span class='headline'>{headline}</span>" if headline else "")
    return (f"<details class='{css_class}'{' open' if unfolded else ''}><summary>{summary}"
            f"</summary><div class='folded' id='{escape_html(anchor)}'>\n{body}\n</div>"
            "</details>")


def header_cell(text: str) -> str:
    """A header with its unit (``"v_x [m/s]"``) on a second line, and a long body name
    (``"dumbbell.v_x"``) broken after its dot, to keep columns narrow."""
    return _header_cell(text) if isinstance(text, str) else _header_cell.__wrapped__(text)


@functools.lru_cache(maxsize=1024)
def _header_cell(text) -> str:
    """:func:`header_cell`, each header formatted once (a page of 1,000 scenarios has 2,400
    velocity tables of a dozen headers, nearly all alike)."""
    name, bracket, unit = str(text).partition(" [")
    body, dot, speed = name.rpartition(".")
    head = (escape_html(body + dot) + "<br>" + escape_html(speed) if dot and len(name) > 8
            else escape_html(name))
    return head + (f"<br><span class='muted'>[{escape_html(unit)}</span>" if bracket else "")


def html_table(header: Sequence[str], rows: Sequence[Sequence], left: int = 1,
               row_classes: Sequence[str] | None = None,
               column_classes: Sequence[str] | None = None) -> str:
    """A table in a horizontally scrolling wrapper; cells are HTML already.

    The first ``left`` columns are left-aligned; ``column_classes`` (one per column, "" for
    none) overrides a column's class (e.g. ``"note"`` for wrapped text).
    """
    def cell_open(i: int) -> str:  # a column's opening tag, made once per table
        cls = column_classes[i] if column_classes and column_classes[i] else (
            "l" if i < left else "")
        return f'<td class="{cls}">' if cls else "<td>"

    def head(i: int, text) -> str:
        cls = column_classes[i] if column_classes and column_classes[i] in (
            "note", "l", "wrap") else ("l" if i < left else "")
        cell = header_cell(text)
        return f'<th class="{cls}">{cell}</th>' if cls else f"<th>{cell}</th>"

    out = ['<div class="scroll"><table><tr>' + "".join(head(i, h) for i, h in enumerate(header))
           + "</tr>"]
    rows = [row if isinstance(row, list | tuple) else list(row) for row in rows]
    opens = [cell_open(i) for i in range(max(map(len, rows), default=0))]
    for k, row in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        out.append(f"<tr{cls}>" + "".join([f"{start}{content}</td>"
                                           for start, content in zip(opens, row)]) + "</tr>")
    out.append("</table></div>")
    return "\n".join(out)


def figure_html(file: str, alt: str, css_class: str = "", caption: str = "",
                svg: bool = True) -> str:
    """A figure's PNG, linked to its SVG (the vector version for a paper) when ``svg``.
    Loaded eagerly: a lazy image not yet scrolled to is left out of a printed page, and a
    report holds at most a few hundred figures (per-scenario figures stop at 60 scenarios)."""
    vector = Path(file).with_suffix(".svg").name
    cls = f' class="{css_class}"' if css_class else ""
    image = (f'<img{cls} src="{FIGURES}/{escape_html(file)}" '
             f'alt="{escape_html(alt)}">')
    if svg:
        image = f'<a href="{FIGURES}/{escape_html(vector)}">{image}</a>'
    link = f" <a href='{FIGURES}/{escape_html(vector)}'>SVG</a>" if svg else ""
    return ("<figure>" + image
            + (f"<figcaption>{caption}{link}</figcaption>" if caption else "") + "</figure>")


def report_figure(figures: dict, file: str, alt: str, css_class: str = "",
                  caption: str = "") -> str:
    """:func:`figure_html` for one of the report's figures, linked to its SVG when the
    report wrote one (``figures["svg"]``)."""
    return figure_html(file, alt, css_class=css_class, caption=caption,
                       svg=file in figures.get("svg", ()))


def markdown_to_html(text: str, heading_shift: int = 1) -> str:
    """The small Markdown subset the harness writes: headings, paragraphs, tables, images,
    lists, ``code`` and **bold**."""
    def inline(line: str) -> str:
        line = escape_html(line)
        line = re.sub(r"!\[([^\]]*)\]\(([^)]+)\)", r'<img src="\2" alt="\1">', line)
        line = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', line)
        line = re.sub(r"`([^`]+)`", r"<code>\1</code>", line)
        return re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", line)

    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        line = lines[i]
        if not line.strip():
            i += 1
            continue
        heading = re.match(r"^(#+)\s+(.*)", line)
        if heading:
            level = min(6, len(heading.group(1)) + heading_shift)
            out.append(f"<h{level}>{inline(heading.group(2))}</h{level}>")
            i += 1
        elif line.startswith("|"):
            block = []
            while i < len(lines) and lines[i].startswith("|"):
                block.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
                i += 1
            header, body = block[0], [r for r in block[1:] if not all(
                re.fullmatch(r":?-+:?", c) for c in r)]
            out.append(html_table(header, [[inline(c) for c in r] for r in body]))
        elif re.match(r"^\s*[-*] ", line):
            items = []
            while i < len(lines) and re.match(r"^\s*[-*] ", lines[i]):
                item = re.sub(r"^\s*[-*] ", "", lines[i])
                items.append(f"<li>{inline(item)}</li>")
                i += 1
            out.append("<ul>" + "".join(items) + "</ul>")
        else:
            paragraph = []
            while i < len(lines) and lines[i].strip() and not re.match(r"^(#|\||\s*[-*] )",
                                                                       lines[i]):
                paragraph.append(lines[i])
                i += 1
            out.append(f"<p>{inline(' '.join(paragraph))}</p>")
    return "\n".join(out)
