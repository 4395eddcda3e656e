"""Reading a user's YAML file (camera, scenario, sweep) with one clear error naming the file."""

from __future__ import annotations

from pathlib import Path

import yaml


def read_yaml_mapping(path: str | Path, kind: str, error: type[Exception], holds: str = "fields") -> dict:
    """The mapping at the top of a YAML file; ``error`` names the file and what is wrong.

    ``kind`` says what the file is ("camera", "scenario", "sweep"); ``holds`` what its top-level
    keys are, for the message when the file is not a mapping.
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise error(f"{path}: {kind} file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{path}: cannot read {kind} file ({exc})") from None
    except yaml.YAMLError as exc:
        raise error(f"{path}: not valid YAML ({exc})".replace("\n", " ")) from None
    if not isinstance(data, dict):
        raise error(f"{path}: a {kind} is a YAML mapping of {holds}, got {type(data).__name__}")
    return data
