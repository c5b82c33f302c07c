"""Writing a hostile file for a loader test: text with lone surrogates kept, or raw bytes."""

from __future__ import annotations

from pathlib import Path


def write_content(path: Path, content: str | bytes) -> Path:
    """Write ``content`` to ``path`` as it is (a ``str`` as UTF-8, lone surrogates included); return the path."""
    if isinstance(content, str):
        path.write_text(content, encoding="utf-8", errors="surrogatepass")
    else:
        path.write_bytes(content)
    return path
