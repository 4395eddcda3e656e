"""Writing scenario data as an ordinary, commented YAML scenario file."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import yaml

#: The comment above each top-level section.
SECTION_COMMENTS = {
    "street": ["The street in a local east/north frame (x east, y north, m) whose origin is given below.",
               "Street coordinates: s along the centreline from its first point, d to its left (m);",
               "lanes and sidewalks are offsets d (y_center_m), lane direction +1 runs toward increasing s."],
    "lamps": ["Surveyed lamps: s along the centreline, d to its left (+) or right (-), m. The camera is",
              "written inline (the paper's scene A camera, Table 2) so this file runs from anywhere."],
    "traffic": ["Assumed night-time arrivals per hour for this class of street (not counts): edit them,",
                "or re-import with --rate CLASS=PER_HOUR. Hour 0 of the profiles is start_hour."],
    "simulation": ["Idle cameras are judged once a second (15 frames): a night ~5x cheaper to simulate."],
    "controllers": ["The controllers compared on the same traffic (savings against always_on)."],
    "year": ["`citysim year`: the site (the street's origin) and its time zone; add a tariff and factors."],
}


class _Dumper(yaml.SafeDumper):
    """Block style for sections, flow style for short leaf lists and mappings."""


def _represent_list(dumper, data):
    flow = all(not isinstance(v, (list, dict)) for v in data) or all(
        isinstance(v, list) and all(not isinstance(x, (list, dict)) for x in v) for v in data) and len(data) <= 4
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


def _represent_dict(dumper, data):
    flow = all(not isinstance(v, (list, dict)) for v in data.values()) and len(data) <= 8
    return dumper.represent_mapping("tag:yaml.org,2002:map", data.items(), flow_style=flow)


_Dumper.add_representer(list, _represent_list)
_Dumper.add_representer(dict, _represent_dict)


def _dump(key: str, value) -> str:
    """One top-level field as YAML: ``key: value`` (a block section when the value nests)."""
    if not isinstance(value, (dict, list)):
        return yaml.safe_dump({key: value}, sort_keys=False, allow_unicode=True, width=100)
    text = yaml.dump(value, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=110)
    if text.startswith(("{", "[")):
        return f"{key}: {text}"
    return f"{key}:\n" + "".join(f"  {line}\n" for line in text.splitlines())


def scenario_text(data: dict, header: list[str] | None = None) -> str:
    """The YAML text of scenario ``data``: ``header`` comment lines, then each top-level field
    with its comment."""
    lines = [f"# {h}".rstrip() for h in (header or [])]
    out = "\n".join(lines) + ("\n\n" if lines else "")
    for key, value in data.items():
        comment = "".join(f"# {c}\n" for c in SECTION_COMMENTS.get(key, []))
        out += ("\n" if comment else "") + comment + _dump(key, value)
    return out


def write_scenario(data: dict, path: str | Path, header: list[str] | None = None) -> Path:
    """Write scenario ``data`` to ``path`` as commented YAML, atomically (a temporary file renamed
    into place, so an interrupted write leaves nothing half-written).

    Parameters
    ----------
    data : the scenario mapping (``scenario_data`` or ``import_street``).
    path : the .yaml file to write (its folder is created).
    header : comment lines for the top of the file (what made it, the licence).

    Returns
    -------
    The path written.
    """
    return write_text(scenario_text(data, header), path)


def write_text(text: str, path: str | Path) -> Path:
    """Write ``text`` to ``path`` atomically (a temporary file renamed into place); the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # an ordinary file, not mkstemp's private 0600
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
