"""Reading a user's YAML file (camera, scenario, sweep) with one clear error naming the file."""

from __future__ import annotations

from pathlib import Path

import yaml

from detector.cliargs import nearest_names


def read_yaml_mapping(path: str | Path, kind: str, error: type[Exception], holds: str = "fields") -> dict:
    """The mapping at the top of a YAML file; ``error`` names the file and what is wrong.

    ``kind`` says what the file is ("camera", "scenario", "sweep"); ``holds`` what its top-level
    keys are, for the message when the file is not a mapping.
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise error(f"{path}: {kind} file not found{_nearby_yaml(path)}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{path}: cannot read {kind} file ({exc})") from None
    except yaml.YAMLError as exc:
        raise error(_yaml_error(path, exc)) from None
    if data is None:
        raise error(f"{path}: the file is empty (or holds only comments); a {kind} is a YAML mapping of "
                    f"{holds}, one `key: value` per line")  # fmt: skip
    if not isinstance(data, dict):
        raise error(f"{path}: a {kind} is a YAML mapping of {holds} (`key: value` lines), "
                    f"got {_what(data)}")  # fmt: skip
    return data


def _yaml_error(path: Path, exc: yaml.YAMLError) -> str:
    """'FILE: not valid YAML at line L, column C: PROBLEM (CONTEXT at line L2)', counted from 1."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).split("\n")[0]
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    context, context_mark = getattr(exc, "context", None), getattr(exc, "context_mark", None)
    if context and context_mark is not None and mark is not None and context_mark.line != mark.line:
        problem += f" ({context} at line {context_mark.line + 1})"
    elif context:
        problem += f" ({context})"
    return f"{path}: not valid YAML{where}: {problem}"


def _what(data: object) -> str:
    """A user's words for what a YAML document held instead of a mapping."""
    if isinstance(data, list):
        return f"a list of {len(data)} items"
    return f"a single value ({data!r})"


def _nearby_yaml(path: Path) -> str:
    """'; did you mean <folder>/x.yaml?' for a near miss among the YAML files beside ``path`` (the
    folder's files are not listed otherwise: a folder may hold many)."""
    folder = path.parent
    if not folder.is_dir():
        return ""
    near = nearest_names(path.name, sorted(p.name for p in folder.iterdir() if p.suffix in (".yaml", ".yml")))
    return f"; did you mean {' or '.join(str(folder / n) for n in near)}?" if near else ""
