"""`make demo` speaks from its first second: the install and the demo each say what they do first."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[3]


def recipe(target: str) -> list[str]:
    """The command lines of a Makefile target (``target:`` up to the next blank line)."""
    lines = (REPO / "Makefile").read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"{target}:"))
    body = []
    for line in lines[start + 1:]:
        if not line.startswith("\t"):
            break
        body.append(line.strip())
    return body


def test_install_and_demo_say_what_they_do_before_they_do_it():
    install, demo = recipe("$(STAMP)"), recipe("demo")
    assert install[0].startswith("@echo ") and "installing" in install[0]
    assert any(line.startswith("@echo ") for line in install[1:install.index("$(PY) -m pip install --quiet -e .")])
    assert demo[0].startswith("@echo ") and demo[1] == "$(PY) -m experiments.demo"
