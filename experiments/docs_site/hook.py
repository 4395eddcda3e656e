"""MkDocs hook: adds the generated reference pages (`experiments.docs_site.reference.PAGES`) to the site.

mkdocs.yml names this file under ``hooks:``; MkDocs calls ``on_files`` before it reads the pages,
so the pages are written from the code of the very checkout being built and never committed.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mkdocs.structure.files import File, Files

# MkDocs loads a hook by its file path: make the project importable as it is when run from the clone
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from experiments.docs_site.reference import PAGES  # noqa: E402


def on_files(files: Files, config) -> Files:
    """Add each generated page under its path in docs/ (e.g. reference/cli.md)."""
    for path, write in PAGES.items():
        files.append(File.generated(config, path, content=write()))
    return files
