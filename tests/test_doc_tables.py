"""Every Markdown table on the user pages (README.md, docs/**/*.md) renders: each row has its
header's number of cells. A pipe inside a cell ends it (GitHub and MkDocs tables, code spans
included) unless escaped as ``\\|``; the file-format reference once split 65 rows this way."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def cells(line: str) -> int:
    """The number of cells of a table row (escaped pipes kept inside their cell)."""
    body = line.strip()
    body = body[1:] if body.startswith("|") else body
    body = body[:-1] if body.endswith("|") and not body.endswith("\\|") else body
    return len(re.split(r"(?<!\\)\|", body))


def tables(text: str):
    """(line number, header cells, [(line number, cells)]) of each table outside code."""
    lines = text.splitlines()
    fenced = False
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif (not fenced and line.lstrip().startswith("|") and i + 1 < len(lines)
              and re.match(r"^\s*\|?\s*:?-{3,}", lines[i + 1])):
            head, rows = cells(line), []
            j = i + 2
            while j < len(lines) and lines[j].lstrip().startswith("|"):
                rows.append((j + 1, cells(lines[j])))
                j += 1
            yield i + 1, head, rows
            i = j
            continue
        i += 1


def test_the_checker_sees_a_split_row():
    bad = "| a | b |\n|---|---|\n| `x` | in \\|x\\| and |y| |\n"
    (_, head, rows), = tables(bad)
    assert head == 2 and rows[0][1] == 4  # `x` | in \|x\| and | y | (empty)


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_every_table_row_has_its_headers_cells(page):
    bad = [f"{page.name}:{n}: {c} cells, header {head}"
           for _, head, rows in tables(page.read_text(encoding="utf-8"))
           for n, c in rows if c != head]
    assert not bad, "\n".join(bad[:10])
