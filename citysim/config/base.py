"""Shared pieces of the scenario schema: the frozen base model and field-path errors.

Cross-field checks inside a model raise ``FieldPathError`` with the path of the
offending field *relative to that model*; ``citysim.config.scenario`` appends it to the
model's own location so the user sees one dotted path from the file's top
(``lamps.camera.tilt_deg``), never "value error at lamps".
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, ValidationError

from detector.camera import format_validation_error


class ScenarioError(ValueError):
    """A scenario that cannot be used; the message starts with the file and the field path."""


class FieldPathError(ValueError):
    """A cross-field check failed at ``path`` (a tuple of keys/indices below the raising model)."""

    def __init__(self, path: tuple[str | int, ...], message: str) -> None:
        super().__init__(message)
        self.path = tuple(path)


class Spec(BaseModel):
    """Base of every scenario section: immutable, unknown keys are errors."""

    model_config = ConfigDict(frozen=True, extra="forbid")


def describe_validation_error(exc: ValidationError, model: type[BaseModel] | None = None) -> str:
    """One line per bad field with its full dotted path (FieldPathError paths appended); an
    unknown field gets the nearest valid names of the section it is in.

    ``model``: the class that was validated; default the ``Spec`` subclass the error is titled
    after (pydantic titles an error with the class name, e.g. "Scenario")."""
    line_errors = []
    for err in exc.errors():
        ctx = err.get("ctx") or {}
        cause = ctx.get("error")
        loc = tuple(err["loc"]) + (cause.path if isinstance(cause, FieldPathError) else ())
        entry = {"type": err["type"], "loc": loc, "input": err.get("input")}
        if ctx:
            entry["ctx"] = ctx
        line_errors.append(entry)
    if model is None:
        model = _spec_named(exc.title)
    return format_validation_error(ValidationError.from_exception_data(exc.title, line_errors), model=model)


def _spec_named(name: str) -> type[Spec] | None:
    """The Spec subclass called ``name``, found among the subclasses already defined."""
    todo = [Spec]
    while todo:
        cls = todo.pop()
        if cls.__name__ == name:
            return cls
        todo.extend(cls.__subclasses__())
    return None
