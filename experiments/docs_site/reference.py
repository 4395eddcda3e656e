"""Reference pages written from the code itself: every command's parser and the scenario schema.

`cli_page` walks `citysim.cli.build_parser()` (each command's subparser) and the parsers of
`python -m detector`; `scenario_page` walks `citysim.config.scenario.Scenario` and every section
model under it. Both return Markdown; nothing here is typed by hand, so the pages cannot drift
from the code. The MkDocs hook (`experiments.docs_site.hook`) adds them to the site at build time.
"""

from __future__ import annotations

import argparse
import types
import typing
from collections.abc import Iterator
from pathlib import Path

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

#: The project folder (this file is experiments/docs_site/reference.py).
ROOT = Path(__file__).resolve().parents[2]
#: A field name's suffix and the unit it stands for (the house rule: every number carries its unit).
UNIT_SUFFIXES = (
    ("_per_kwh", "currency / kWh"), ("_kg_co2_per_kwh", "kg CO2 / kWh"), ("_per_hour", "1 / h"),
    ("_per_min", "1 / min"), ("_per_frame", "1 / frame"), ("_kmh", "km/h"), ("_mps", "m/s"),
    ("_m2", "m²"), ("_mm", "mm"), ("_ms", "ms"), ("_m", "m"), ("_s", "s"), ("_deg", "degrees"),
    ("_hz", "Hz"), ("_w", "W"), ("_dn", "digital numbers (8-bit grey levels)"), ("_px", "pixels"),
    ("_hour", "clock hour"), ("_fraction", "fraction (0-1)"), ("_probability", "probability (0-1)"),
)


def unit_of(name: str) -> str:
    """The unit a field's name carries (``height_m`` -> m), or "" when the name has none."""
    for suffix, unit in UNIT_SUFFIXES:
        if name.endswith(suffix):
            return unit
    return ""


def _cell(text: object) -> str:
    """Text safe inside a Markdown table cell."""
    return str(text).replace("|", "\\|").replace("\n", " ").strip()


# ---------------------------------------------------------------- command line


def _option_rows(parser: argparse.ArgumentParser) -> Iterator[str]:
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
            continue
        name = ", ".join(f"`{s}`" for s in action.option_strings) or f"`{action.metavar or action.dest}`"
        if action.option_strings and action.nargs != 0:
            name += f" `{action.metavar or action.dest.upper()}`"
        default = action.default
        shown = "" if default in (None, argparse.SUPPRESS, False) or not action.option_strings else f"`{default}`"
        choices = f"One of: {', '.join(map(str, action.choices))}." if action.choices else ""
        required = " (required)" if action.required and action.option_strings else ""
        helped = _cell(action.help or "")
        if helped and choices and not helped.endswith("."):
            helped += "."
        what = " ".join(part for part in (helped, choices) if part)
        yield f"| {name}{required} | {what} | {shown} |"


def parser_section(parser: argparse.ArgumentParser, level: str = "##") -> str:
    """One command's section: its usage line, description and a table of its arguments."""
    usage = parser.format_usage().removeprefix("usage: ").strip()
    lines = [f"{level} `{parser.prog}`", "", parser.description or "", "", "```text", usage, "```", "",
             "| argument | what | default |", "|---|---|---|", *_option_rows(parser), ""]
    return "\n".join(lines)


def citysim_subparsers() -> dict[str, argparse.ArgumentParser]:
    """Every `citysim` command's subparser by name, in the order `citysim --help` lists them."""
    from citysim.cli import build_parser

    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    raise RuntimeError("citysim's parser has no commands")


def detector_parsers() -> dict[str, argparse.ArgumentParser]:
    """`python -m detector`'s two parsers: detecting on a video, and training a camera's model."""
    from detector.__main__ import _detect_parser, _train_parser

    return {"detect": _detect_parser(), "train": _train_parser()}


def cli_page() -> str:
    """The command-line reference page: every `citysim` command, then `python -m detector`."""
    parts = ["# Command line", "",
             "Written from the programs' own parsers when the site is built: every option below is one "
             "the program accepts. `COMMAND --help` prints the same.", ""]
    parts += [parser_section(p) for p in citysim_subparsers().values()]
    parts += [parser_section(p) for p in detector_parsers().values()]
    return "\n".join(parts)


# ---------------------------------------------------------------- scenario schema


def _models_in(annotation: object) -> list[type[BaseModel]]:
    """The pydantic models a field's type holds (itself, inside a tuple, a union or Optional)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in typing.get_args(annotation) for m in _models_in(arg)]


def type_name(annotation: object) -> str:
    """A short readable name of a field's type (``float``, ``tuple[ControllerSpec, ...]``)."""
    if isinstance(annotation, type) and not typing.get_args(annotation):
        return annotation.__name__
    text = repr(annotation)
    for prefix in ("typing.", "citysim.config.scenario.", "citysim.config.street.", "citysim.config.traffic.",
                   "citysim.config.year.", "citysim.config.motion.", "citysim.config.kinds.", "pathlib."):
        text = text.replace(prefix, "")
    return text.replace("<class '", "").replace("'>", "").replace("NoneType", "None")


def _default(info) -> str:
    if info.default is PydanticUndefined and info.default_factory is None:
        return "required"
    value = info.default_factory() if info.default is PydanticUndefined else info.default
    if isinstance(value, BaseModel):
        return "its section's defaults"
    if isinstance(value, tuple | list) and value and isinstance(value[0], BaseModel):
        return ", ".join(f"`{getattr(v, 'name', type(v).__name__)}`" for v in value)
    return f"`{value!r}`"


def _limits(info) -> str:
    found = []
    for meta in info.metadata:
        for key, sign in (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<")):
            if getattr(meta, key, None) is not None:
                found.append(f"{sign} {getattr(meta, key)}")
    return f" ({', '.join(found)})" if found else ""


def yaml_comments(text: str) -> dict[str, str]:
    """Each key's comment in a commented scenario file, by dotted path (``lamps.luminaire.hold_s``).

    A key's comment is the ``#`` text at the end of its line, else the comment lines right above
    it; keys of list items (``- {..}``) are not followed. Used where a field has no description.
    """
    found: dict[str, str] = {}
    stack: list[tuple[int, str]] = []
    above: list[str] = []
    for raw in text.splitlines():
        stripped = raw.strip()
        if stripped.startswith("#"):
            above.append(stripped.lstrip("#").strip())
            continue
        indent = len(raw) - len(raw.lstrip())
        key, colon, rest = stripped.partition(":")
        if not colon or not key.replace("_", "").isalnum() or stripped.startswith("-"):
            above = []
            continue
        while stack and stack[-1][0] >= indent:
            stack.pop()
        stack.append((indent, key))
        inline = rest.partition(" #")[2].strip()
        comment = inline or " ".join(above).strip()
        if comment:
            found[".".join(k for _, k in stack)] = comment
        above = []
    return found


def _model_table(model: type[BaseModel], path: str, comments: dict[str, str]) -> Iterator[str]:
    yield f"## `{path}`" if path else "## top level"
    yield ""
    doc = " ".join((model.__doc__ or "").strip().split("\n\n")[0].split())
    if doc and not doc.startswith(model.__name__ + "("):  # pydantic's own repr when there is none
        yield doc
        yield ""
    yield "| field | type | unit | default | description |"
    yield "|---|---|---|---|---|"
    for name, info in model.model_fields.items():
        comment = comments.get(f"{path}.{name}".lstrip("."))
        described = (info.description or (f"*suburban_night:* {comment}" if comment else "")) + _limits(info)
        yield (f"| `{name}` | {_cell(type_name(info.annotation))} | {unit_of(name)} | {_cell(_default(info))} "
               f"| {_cell(described)} |")
    yield ""


def scenario_models() -> list[tuple[str, type[BaseModel]]]:
    """Every model of the scenario schema with its dotted path, top level first, each once."""
    from citysim.config.scenario import Scenario

    found: list[tuple[str, type[BaseModel]]] = []
    seen: set[type[BaseModel]] = set()
    queue: list[tuple[str, type[BaseModel]]] = [("", Scenario)]
    while queue:
        path, model = queue.pop(0)
        if model in seen:
            continue
        seen.add(model)
        found.append((path, model))
        for name, info in model.model_fields.items():
            sub = f"{path}.{name}" if path else name
            queue += [(sub, m) for m in _models_in(info.annotation) if m not in seen]
    return found


#: Commented scenario files whose comments describe fields the models leave undescribed.
COMMENTED_SCENARIOS = ("scenarios/suburban_night.yaml",)


def scenario_page(root: Path = ROOT) -> str:
    """The scenario-schema reference page: one table per section of the YAML file; ``root`` is the
    project folder (its commented scenarios fill in field descriptions)."""
    comments: dict[str, str] = {}
    for name in COMMENTED_SCENARIOS:
        comments |= yaml_comments((root / name).read_text())
    parts = ["# Scenario schema", "",
             "Written from the pydantic models of `citysim.config` when the site is built. A scenario "
             "file is a YAML mapping of these sections; unknown keys are errors, and an invalid value "
             "is reported with its dotted path (`lamps.camera.tilt_deg`). The unit comes from the "
             "field's name (every number carries its unit); limits are in brackets. Descriptions marked "
             "*suburban_night:* are that scenario's comments on its own value, for fields the models "
             "leave undescribed.", ""]
    for path, model in scenario_models():
        parts += list(_model_table(model, path, comments))
    return "\n".join(parts)


#: Generated page path (inside docs/) -> the function that writes it.
PAGES: dict[str, types.FunctionType] = {"reference/cli.md": cli_page, "reference/scenario.md": scenario_page}
