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
        raise error(f"{path}: not valid YAML ({exc})".replace("\n", " ")) from None
    if not isinstance(data, dict):
        raise error(f"{path}: a {kind} is a YAML mapping of {holds}, got {type(data).__name__}")
    return data


def _nearby_yaml(path: Path) -> str:
    """'; did you mean <folder>/x.yaml?' for a near miss among the YAML files beside ``path`` (the
    folder's files are not listed otherwise: a folder may hold many)."""
    folder = path.parent
    if not folder.is_dir():
        return ""
    near = nearest_names(path.name, sorted(p.name for p in folder.iterdir() if p.suffix in (".yaml", ".yml")))
    return f"; did you mean {' or '.join(str(folder / n) for n in near)}?" if near else ""
