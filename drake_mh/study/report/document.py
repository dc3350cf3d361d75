"""A report as a list of blocks, rendered to markdown (``report.md``) and to one
self-contained HTML page (``index.html``: figures as base64 PNG, animations in
``<iframe srcdoc>``, inline CSS, no external resource)."""

from __future__ import annotations

import base64
import html
import re
from dataclasses import dataclass, field

from drake_mh.study.report.plots import FigureFile
from drake_mh.study.report.tables import Table


@dataclass(frozen=True)
class Heading:
    """Section title."""

    text: str
    level: int = 2


@dataclass(frozen=True)
class Paragraph:
    """Text paragraph; in HTML, inline markdown ```code``` and ``**bold**`` are rendered."""

    text: str


@dataclass(frozen=True)
class Preformatted:
    """Text shown verbatim (e.g. the study's own markdown summary)."""

    text: str


@dataclass(frozen=True)
class Animation:
    """An HTML page (Meshcat static HTML) embedded in the page, linked from markdown.

    Attributes:
        path: path relative to the results folder.
        title: caption.
        page: the page's HTML text, or ``None`` to only link it.
    """

    path: str
    title: str
    page: str | None


@dataclass(frozen=True)
class Markdown:
    """Markdown text from a study (its summary): verbatim in ``report.md``; in HTML, headings,
    pipe tables, fenced code and paragraphs are rendered, with inline ```code``` and ``**bold**``."""

    text: str


@dataclass(frozen=True)
class Link:
    """A link to a local file (relative path), e.g. another report."""

    path: str
    text: str


@dataclass
class Document:
    """Ordered report blocks."""

    title: str
    blocks: list = field(default_factory=list)

    def add(self, block) -> None:
        """Appends a block (Heading, Paragraph, Preformatted, Table, FigureFile, Animation, Link)."""
        self.blocks.append(block)


def _md_cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def to_markdown(doc: Document) -> str:
    """Renders the document as markdown; figures link to ``figures/<name>.png``."""
    lines = [f"# {doc.title}", ""]
    for block in doc.blocks:
        if isinstance(block, Heading):
            lines += ["#" * block.level + " " + block.text, ""]
        elif isinstance(block, Paragraph):
            lines += [block.text, ""]
        elif isinstance(block, (Preformatted, Markdown)):
            lines += [block.text.rstrip(), ""]
        elif isinstance(block, Table):
            lines.append("| " + " | ".join(_md_cell(h) for h in block.headers) + " |")
            lines.append("|" + "|".join("---" for _ in block.headers) + "|")
            for row in block.rows:
                lines.append("| " + " | ".join(_md_cell(c) for c in row) + " |")
            lines.append("")
            if block.caption:
                lines += [f"*{block.caption}*", ""]
        elif isinstance(block, FigureFile):
            lines += [f"![{block.caption}](figures/{block.name}.png)", "", f"*{block.caption}*", ""]
        elif isinstance(block, Animation):
            lines += [f"[{block.title}]({block.path})", ""]
        elif isinstance(block, Link):
            lines += [f"[{block.text}]({block.path})", ""]
    return "\n".join(lines).rstrip() + "\n"


_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;max-width:1320px;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{font-size:1.25em;margin-top:1.6em;border-bottom:1px solid #ddd}h3{font-size:1.05em}
table{border-collapse:collapse;margin:.5em 0;font-size:.88em}
th,td{border:1px solid #ccc;padding:.25em .5em;text-align:right}th.name{text-align:left}th{background:#f3f3f3}
td:first-child,th:first-child{text-align:left}
td{white-space:nowrap}td.name{text-align:left}td.text,th.text{white-space:normal;text-align:left;min-width:14em}
.caption{color:#555;font-size:.85em;font-style:italic;margin:.2em 0 1em}
code{background:#f3f3f3;padding:0 .25em;border-radius:3px;font-size:.92em}
img{max-width:100%;height:auto}pre{background:#f7f7f7;padding:.8em;overflow-x:auto;font-size:.85em}
iframe{width:100%;height:600px;border:1px solid #ccc}
.scroll{overflow-x:auto}
"""

#: table cells longer than this may wrap (text); shorter ones (numbers, names) never do
WRAP_ABOVE = 40


def inline_html(text: str) -> str:
    """Escapes ``text`` for HTML and renders inline markdown: ```code``` and ``**bold**``."""
    out = []
    for i, part in enumerate(re.split(r"(`[^`]+`)", str(text))):
        if i % 2:
            out.append(f"<code>{html.escape(part[1:-1])}</code>")
        else:
            out.append(re.sub(r"\*\*(\S(?:.*?\S)?)\*\*", r"<strong>\1</strong>", html.escape(part)))
    return "".join(out)


def _header(text, kind: str = "") -> str:
    """A header cell aligned like its column (``kind``: ``""`` numbers, ``"name"`` words,
    ``"text"`` long text); a unit in brackets stays on one line (``[m + rad]``)."""
    body = re.sub(r"\[[^\]]*\]", lambda m: m.group(0).replace(" ", "\u00a0"), str(text))
    css = f' class="{kind}"' if kind else ""
    return f"<th{css}>{inline_html(body)}</th>"


def _cell_kind(text: str) -> str:
    """``"text"`` (long, may wrap), ``""`` (a number or empty: right-aligned, never wraps) or ``"name"``."""
    if len(text) > WRAP_ABOVE:
        return "text"
    return "" if not text.strip() or _NUMBER.fullmatch(text.strip()) else "name"


def _column_kind(cells: list) -> str:
    """A column's alignment: ``"text"`` if any cell is long text, ``""`` if every cell is a
    number (or empty), else ``"name"``."""
    kinds = {_cell_kind(str(c)) for c in cells}
    return "text" if "text" in kinds else "name" if "name" in kinds else ""


_NUMBER = re.compile(r"[-+]?(\d[\d,]*\.?\d*|\.\d+)(e[-+]?\d+)?\s*(%|x|[a-zµ]{1,3})?(\s*\(.*\))?|-|inf|-inf|nan",
                     re.IGNORECASE)


def _cell(text) -> str:
    """A body cell: long text may wrap (left-aligned), numbers never wrap (right-aligned),
    short words (names) are left-aligned."""
    text = str(text)
    kind = _cell_kind(text)
    css = f' class="{kind}"' if kind else ""
    return f"<td{css}>{inline_html(text)}</td>"


def _split_row(line: str) -> list[str]:
    cells = re.split(r"(?<!\\)\|", line.strip().strip("|"))
    return [c.strip().replace("\\|", "|") for c in cells]


def markdown_blocks(text: str) -> list:
    """Parses the markdown subset studies write: ``#`` headings, pipe tables (a row of
    ``---`` after the header), fenced code and paragraphs; returns report blocks."""
    blocks: list = []
    lines = text.splitlines()
    i = 0
    paragraph: list[str] = []

    def flush() -> None:
        if paragraph:
            blocks.append(Paragraph(" ".join(paragraph)))
            paragraph.clear()

    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith("```"):
            flush()
            code = []
            i += 1
            while i < len(lines) and not lines[i].strip().startswith("```"):
                code.append(lines[i])
                i += 1
            blocks.append(Preformatted("\n".join(code)))
        elif re.match(r"^#{1,6}\s", stripped):
            flush()
            hashes = len(stripped) - len(stripped.lstrip("#"))
            blocks.append(Heading(stripped[hashes:].strip(), level=min(6, max(3, hashes))))
        elif stripped.startswith("|") and i + 1 < len(lines) and re.match(r"^\|?\s*:?-{3,}", lines[i + 1].strip()):
            flush()
            headers = _split_row(stripped)
            rows = []
            i += 2
            while i < len(lines) and lines[i].strip().startswith("|"):
                rows.append(_split_row(lines[i]))
                i += 1
            blocks.append(Table(headers, rows))
            continue
        elif not stripped:
            flush()
        else:
            paragraph.append(stripped)
        i += 1
    flush()
    return blocks


def to_html(doc: Document) -> str:
    """Renders the document as one self-contained HTML page."""
    esc = html.escape
    blocks = []
    for block in doc.blocks:
        blocks.extend(markdown_blocks(block.text) if isinstance(block, Markdown) else [block])
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{esc(doc.title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{esc(doc.title)}</h1>",
    ]
    for block in blocks:
        if isinstance(block, Heading):
            level = min(6, max(2, block.level))
            parts.append(f"<h{level}>{esc(block.text)}</h{level}>")
        elif isinstance(block, Paragraph):
            parts.append(f"<p>{inline_html(block.text)}</p>")
        elif isinstance(block, Preformatted):
            parts.append(f"<pre>{esc(block.text)}</pre>")
        elif isinstance(block, Table):
            kinds = [_column_kind([row[j] for row in block.rows if j < len(row)]) for j in range(len(block.headers))]
            head = "".join(_header(h, kind) for h, kind in zip(block.headers, kinds))
            body = "".join("<tr>" + "".join(_cell(c) for c in row) + "</tr>" for row in block.rows)
            parts.append(f'<div class="scroll"><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>')
            if block.caption:
                parts.append(f'<p class="caption">{inline_html(block.caption)}</p>')
        elif isinstance(block, FigureFile):
            data = base64.b64encode(block.png).decode("ascii")
            parts.append(f'<figure><img alt="{esc(block.caption)}" src="data:image/png;base64,{data}">')
            parts.append(f'<figcaption class="caption">{esc(block.caption)}</figcaption></figure>')
        elif isinstance(block, Animation):
            parts.append(f"<h3>{esc(block.title)}</h3>")
            if block.page is not None:
                parts.append(f'<iframe title="{esc(block.title)}" srcdoc="{esc(block.page, quote=True)}"></iframe>')
            parts.append(f'<p class="caption">file: <a href="{esc(block.path)}">{esc(block.path)}</a></p>')
        elif isinstance(block, Link):
            parts.append(f'<p><a href="{esc(block.path)}">{esc(block.text)}</a></p>')
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
