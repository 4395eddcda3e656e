"""Every command the documentation shows is accepted by its program; the cheap ones are run.

Parsed (all): each `make`, `citysim`, `python -m detector` and `python -m experiments.*` line of
a ```bash block in README.md and docs/ goes through the program's real parser (make: the
Makefile's targets). Run: every `--help` line, and every `citysim run` of 10 simulated seconds or
less (its --out moved into a temporary folder).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.docs.commands import ROOT, CommandError, DocCommand, check_command, doc_commands

COMMANDS = doc_commands()
#: A documented run this short is run by the test, not only parsed.
RUN_AT_MOST_S = 10.0


def _id(command: DocCommand) -> str:
    return f"{command.page}:{command.line[:60]}"


def test_the_docs_show_commands_of_every_kind():
    programs = {c.program for c in COMMANDS}
    assert {"make", "citysim", "python -m detector"} <= {p.removeprefix(".venv/bin/") for p in programs}
    assert any(c.page == "README.md" for c in COMMANDS)


@pytest.mark.parametrize("command", COMMANDS, ids=_id)
def test_documented_command_parses(command: DocCommand):
    check_command(command)


def test_a_wrong_option_is_caught():
    """The check itself can fail: a misspelt option and a missing make target are refused."""
    bad = DocCommand("x.md", "citysim run s.yaml --out o --duratoin 5",
                     ("citysim", "run", "s.yaml", "--out", "o", "--duratoin", "5"))
    with pytest.raises(CommandError, match="duratoin"):
        check_command(bad)
    with pytest.raises(CommandError, match="no Makefile target"):
        check_command(DocCommand("x.md", "make everything", ("make", "everything")))


def _python_argv(command: DocCommand) -> list[str]:
    if command.program.removeprefix(".venv/bin/") == "citysim":
        return [sys.executable, "-m", "citysim", *command.args]
    return [sys.executable, "-m", command.program.removeprefix("python -m "), *command.args]


HELP_LINES = [c for c in COMMANDS if "--help" in c.args and c.program != "make"]


@pytest.mark.parametrize("command", HELP_LINES, ids=_id)
def test_documented_help_runs(command: DocCommand):
    done = subprocess.run(_python_argv(command), cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "usage:" in done.stdout


def _short_run(command: DocCommand) -> bool:
    args = command.args
    if command.program.removeprefix(".venv/bin/") != "citysim" or args[:1] != ["run"] or "--duration" not in args:
        return False
    return float(args[args.index("--duration") + 1]) <= RUN_AT_MOST_S


SHORT_RUNS = [c for c in COMMANDS if _short_run(c)]


def test_the_docs_show_a_short_run():
    assert SHORT_RUNS, "the getting-started page should show a run short enough for the test to run"


@pytest.mark.slow
@pytest.mark.parametrize("command", SHORT_RUNS, ids=_id)
def test_documented_short_run_runs(command: DocCommand, tmp_path):
    argv = _python_argv(command)
    out = argv.index("--out") + 1
    argv[out] = str(tmp_path / "run")
    done = subprocess.run([*argv, "--no-progress"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["controllers"], "a run writes at least one controller's figures"
