"""MkDocs hooks (``hooks:`` in mkdocs.yml).

``docs/benchmarks.md`` holds the marker ``<!-- include: benchmarks/RESULTS.md -->``; at build
time it is replaced by that file (relative to the repository root), so the recorded results
live in one place and the site shows the latest. Its title is dropped and its other headings
are moved down one level to sit under the page's section (not inside fenced code blocks), and
its relative links, which point into the repository rather than the site, become plain text.
``mkdocs serve`` watches the included files.
"""

from __future__ import annotations

import re
from pathlib import Path

MARKER = re.compile(r"<!--\s*include:\s*(?P<path>[^\s>]+)\s*-->")
FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^(#{1,5}) ")
# [text](target) or ![alt](target), the target neither absolute (scheme:, /) nor an anchor
RELATIVE_LINK = re.compile(r"!?\[(?P<text>[^\]]*)\]\((?P<target>(?![a-z][a-z0-9+.-]*:|/|#)"
                           r"[^)\s]+)\)")


def _root(config) -> Path:
    return Path(config.config_file_path).resolve().parent


def _adapt(text: str) -> str:
    """Drop the file's title (a leading level-1 heading), shift the other headings down one
    level and unlink relative links, outside code fences."""
    lines = text.lstrip("\n").splitlines()
    if lines and lines[0].startswith("# "):
        lines = lines[1:]
    out, fenced = [], False
    for line in lines:
        if FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            line = HEADING.sub(lambda m: "#" + m.group(1) + " ", line)
            line = RELATIVE_LINK.sub(lambda m: f"{m.group('text')} (`{m.group('target')}`)",
                                     line)
        out.append(line)
    return "\n".join(out) + "\n"


def on_page_markdown(markdown: str, page, config, files) -> str:
    root = _root(config)

    def include(match: re.Match) -> str:
        path = root / match.group("path")
        if not path.is_file():
            raise FileNotFoundError(f"{page.file.src_path}: included file {path} not found")
        return _adapt(path.read_text(encoding="utf-8"))

    return MARKER.sub(include, markdown)


def on_serve(server, config, builder):
    root = _root(config)
    for page in Path(config.docs_dir).rglob("*.md"):
        for m in MARKER.finditer(page.read_text(encoding="utf-8")):
            server.watch(str(root / m.group("path")))
    return server
