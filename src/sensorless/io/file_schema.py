"""Declared file formats: pydantic models, readable errors, YAML files and format versions.

A file format of the library (a scenario, a fitted threshold) is declared
once as pydantic models derived from :class:`FileModel`: unknown keys are
refused, a string is never read as a number, numbers are finite. This module
turns what pydantic finds into one :class:`~sensorless.exceptions.FileFormatError`
that lists every problem with the dotted path of its field, what was expected
and what came, and, for an unknown key, the closest allowed keys
(``controller.bandwith: unknown key; did you mean 'bandwidth'?``).

Unions are validated by exactly one member, chosen from the value
(:func:`one_of`), so that a mistake gives one message, not one per member.
Per-joint values check their length against ``n_dof`` when the validation
context holds it (``model_validate(data, context={"n_dof": 6})``).

:func:`read_yaml_mapping` reads a YAML file as a mapping and refuses, naming
the file, a binary file, text that is not UTF-8, broken YAML, a key given
twice and anything but a mapping at the top. :func:`check_format_version`
refuses a file written in a newer format than the library reads.
"""

from __future__ import annotations

import difflib
import reprlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Union, get_args

import yaml
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    ValidationError,
    ValidationInfo,
)
from pydantic_core import PydanticCustomError

from .._version import __version__
from ..exceptions import FileFormatError, one_line

__all__ = [
    "Count",
    "FileModel",
    "Fraction",
    "NonNegative",
    "PerJoint",
    "PerJointFraction",
    "PerJointNonNegative",
    "PerJointPositive",
    "Positive",
    "PositiveInt",
    "Problem",
    "Vector3",
    "absent",
    "check_format_version",
    "context_n_dof",
    "did_you_mean",
    "file_error",
    "format_path",
    "joint_list",
    "known_name",
    "one_of",
    "per_joint",
    "problems_of",
    "read_yaml_mapping",
    "shown",
    "version_field",
]

Loc = tuple[str | int, ...]


class FileModel(BaseModel):
    """Base of every declared file section: no unknown keys, no conversions, finite numbers."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


def _no_default(schema: dict[str, Any]) -> None:
    schema.pop("default", None)


def absent(description: str) -> Any:
    """A key that may be left out but not set to null; its meaning when absent is described."""
    return Field(default=None, description=description, json_schema_extra=_no_default)


# ----------------------------------------------------------------------------- unions


@dataclass(frozen=True)
class _Choice:
    """A union validated by one member: ``members`` by name, what to say when none fits."""

    name: str
    key: str | None
    members: tuple[str, ...]
    expected: str


_CHOICES: dict[str, _Choice] = {}
_MEMBERS: dict[str, Any] = {}


def one_of(
    name: str,
    members: Mapping[str, Any],
    *,
    key: str | None = None,
    default: str | None = None,
    pick: Callable[[Any], str | None] | None = None,
    expected: str,
) -> Any:
    """A union of ``members`` validated by the one member the value selects.

    With ``key``, a mapping selects the member named by its ``key`` entry
    (``default`` when the entry is absent); otherwise ``pick(value)`` names it.
    ``expected`` says in words what fits (for a value that selects nothing).
    """

    def choose(value: Any) -> str | None:
        if pick is not None:
            return pick(value)
        if isinstance(value, Mapping):
            kind = value.get(key, default)
            return kind if isinstance(kind, str) else None
        if isinstance(value, BaseModel):
            return getattr(value, str(key), None)
        return None

    def discriminate(value: Any) -> str:
        chosen = choose(value)
        known = isinstance(chosen, str) and chosen in members
        return f"<{name}:{chosen}>" if known else f"<?{name}>"

    _CHOICES[name] = _Choice(name, key, tuple(members), expected)
    tagged = []
    for member, annotation in members.items():
        _MEMBERS[f"<{name}:{member}>"] = annotation
        tagged.append(Annotated[annotation, Tag(f"<{name}:{member}>")])
    return Annotated[Union[tuple(tagged)], Discriminator(discriminate)]  # noqa: UP007


# ----------------------------------------------------------------------------- per joint


def context_n_dof(info: ValidationInfo) -> int | None:
    """The number of joints the validation context gives (``context={"n_dof": n}``), if any."""
    context = info.context
    return context.get("n_dof") if isinstance(context, Mapping) else None


def known_name(kind: str, options: Callable[[], Sequence[str]]) -> Callable[[str], str]:
    """A validator: the text must be one of ``options()`` (e.g. the built-in robots)."""

    def check(name: str) -> str:
        choices = list(options())
        if name not in choices:
            raise PydanticCustomError(
                f"unknown_{kind}",
                "unknown {kind} {name}{hint}",
                {"kind": kind, "name": repr(name), "hint": did_you_mean(name, choices)},
            )
        return name

    return check


def _joint_count(value: Any, info: ValidationInfo) -> Any:
    n_dof = context_n_dof(info)
    if isinstance(value, list) and n_dof is not None and len(value) != n_dof:
        raise PydanticCustomError(
            "joint_count",
            "expected one number for every joint or a list of {n_dof} (one per joint); "
            "got {count} value(s)",
            {"n_dof": n_dof, "count": len(value)},
        )
    return value


def _exact_count(value: Any, info: ValidationInfo) -> Any:
    n_dof = context_n_dof(info)
    if n_dof is not None and len(value) != n_dof:
        raise PydanticCustomError(
            "joint_count",
            "expected {n_dof} values (one per joint); got {count}",
            {"n_dof": n_dof, "count": len(value)},
        )
    return value


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def per_joint(item: Any, name: str) -> Any:
    """One number for every joint, or a list of one number per joint (``item`` each)."""
    union = one_of(
        name,
        {"number": item, "list": list[item]},
        pick=lambda v: "list" if isinstance(v, list) else ("number" if _is_number(v) else None),
        expected="a number or a list of numbers (one per joint)",
    )
    return Annotated[union, AfterValidator(_joint_count)]


def joint_list(item: Any) -> Any:
    """A list of exactly one ``item`` per joint."""
    return Annotated[list[item], AfterValidator(_exact_count)]


Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
Fraction = Annotated[float, Field(ge=0, lt=1)]
Count = Annotated[int, Field(ge=0)]
PositiveInt = Annotated[int, Field(ge=1)]
Vector3 = Annotated[list[float], Field(min_length=3, max_length=3)]

if TYPE_CHECKING:
    PerJoint = float | list[float]
    PerJointPositive = float | list[float]
    PerJointNonNegative = float | list[float]
    PerJointFraction = float | list[float]
else:
    PerJoint = per_joint(float, "per_joint")
    PerJointPositive = per_joint(Positive, "per_joint_positive")
    PerJointNonNegative = per_joint(NonNegative, "per_joint_nonnegative")
    PerJointFraction = per_joint(Fraction, "per_joint_fraction")


def version_field(current: int, what: str) -> Any:
    """The ``format_version`` key of a ``what`` file: ``current`` when absent."""
    return Field(
        default=current,
        ge=1,
        le=current,
        description=f"Version of the {what} file format (absent: {current}, this one).",
    )


# ----------------------------------------------------------------------------- problems


@dataclass(frozen=True)
class Problem:
    """One problem of a file: the path of its field and what is wrong."""

    path: Loc
    message: str

    def __str__(self) -> str:
        where = format_path(self.path)
        return f"{where}: {self.message}" if where else self.message


def format_path(path: Loc) -> str:
    """``("collisions", 3, "peak")`` → ``collisions[3].peak`` (union tags left out)."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        elif not part.startswith("<"):
            text += f".{part}" if text else part
    return text


_SHOW = reprlib.Repr()
_SHOW.maxstring, _SHOW.maxother, _SHOW.maxlist, _SHOW.maxdict = 40, 40, 4, 3


def shown(value: Any) -> str:
    """A value as the user wrote it, shortened: YAML words for null and booleans."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, Mapping):
        return f"a mapping {_SHOW.repr(dict(value))}"
    if isinstance(value, list):
        return f"a list {_SHOW.repr(value)}"
    return _SHOW.repr(value)


def did_you_mean(name: Any, options: Sequence[str]) -> str:
    """``"; did you mean 'x'?"``, or the allowed options when none is close."""
    close = difflib.get_close_matches(str(name), list(options), n=3, cutoff=0.6)
    if close:
        quoted = [repr(c) for c in close]
        listed = quoted[0] if len(quoted) == 1 else ", ".join(quoted[:-1]) + " or " + quoted[-1]
        return f"; did you mean {listed}?"
    return f"; allowed: {', '.join(sorted(options))}"


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [model for arg in get_args(annotation) for model in _models_in(arg)]


def _keys_at(root: type[BaseModel], loc: Loc) -> list[str]:
    """Keys allowed by the model at ``loc`` (a path of pydantic's, with union tags)."""
    models: list[type[BaseModel]] = [root]
    for part in loc:
        if isinstance(part, int):
            continue
        if part.startswith("<"):
            models = _models_in(_MEMBERS.get(part))
            continue
        fields = [m.model_fields[part] for m in models if part in m.model_fields]
        if not fields:
            return []
        models = _models_in(fields[0].annotation)
    return sorted(models[0].model_fields) if len(models) == 1 else []


_EXPECTED = {
    "float_type": "a number",
    "int_type": "an integer",
    "string_type": "text",
    "bool_type": "true or false",
    "list_type": "a list",
    "dict_type": "a mapping (key: value)",
    "model_type": "a mapping (key: value)",
    "finite_number": "a finite number",
    "greater_than": "a value > {gt}",
    "greater_than_equal": "a value >= {ge}",
    "less_than": "a value < {lt}",
    "less_than_equal": "a value <= {le}",
    "too_short": "at least {min_length} item(s)",
    "too_long": "at most {max_length} item(s)",
    "literal_error": "one of {expected}",
}


def _choice_problem(choice: _Choice, loc: Loc, value: Any) -> Problem:
    options = ", ".join(choice.members)
    if choice.key is None or not isinstance(value, Mapping):
        return Problem(loc, f"expected {choice.expected}; got {shown(value)}")
    where = (*loc, choice.key)
    if choice.key not in value:
        typo = difflib.get_close_matches(choice.key, [str(k) for k in value], n=1, cutoff=0.6)
        hint = f" (is {typo[0]!r} a typo of it?)" if typo else ""
        return Problem(where, f"required key is missing{hint}; expected one of: {options}")
    given = value[choice.key]
    hint = did_you_mean(given, choice.members) if isinstance(given, str) else ""
    if not hint.startswith("; did you mean"):
        hint = f"; expected one of: {options}"
    return Problem(where, f"unknown {choice.key} {shown(given)}{hint}")


def _problem(error: Any, root: type[BaseModel], prefix: Loc) -> Problem:
    loc: Loc = (*prefix, *error["loc"])
    kind, ctx, value = error["type"], error.get("ctx") or {}, error.get("input")
    if kind == "extra_forbidden":
        name = error["loc"][-1]
        return Problem(loc, "unknown key" + did_you_mean(name, _keys_at(root, error["loc"][:-1])))
    if kind == "missing":
        return Problem(loc, "required key is missing")
    if kind == "union_tag_invalid":
        return _choice_problem(_CHOICES[str(ctx["tag"])[2:-1]], loc, value)
    if "field" in ctx:  # a check across fields, about one of them
        return Problem((*loc, ctx["field"]), str(error["msg"]))
    if kind in _EXPECTED:
        return Problem(loc, f"expected {_EXPECTED[kind].format(**ctx)}; got {shown(value)}")
    return Problem(loc, str(error["msg"]).removeprefix("Value error, "))


def problems_of(exc: ValidationError, root: type[BaseModel], prefix: Loc = ()) -> list[Problem]:
    """The problems pydantic found validating ``root``, each with its field path."""
    problems: list[Problem] = []
    for error in exc.errors():
        problem = _problem(error, root, prefix)
        if problem not in problems:
            problems.append(problem)
    return problems


def file_error(source: str, problems: Sequence[Problem], limit: int = 12) -> FileFormatError:
    """One error for all ``problems`` of ``source`` (e.g. ``"scenario file run.yaml"``)."""
    if len(problems) == 1:
        return FileFormatError(f"{source}: {problems[0]}")
    listed = " ".join(f"({k}) {p}" for k, p in enumerate(problems[:limit], start=1))
    more = f" ... and {len(problems) - limit} more" if len(problems) > limit else ""
    return FileFormatError(f"{source} has {len(problems)} problems: {listed}{more}")


# ----------------------------------------------------------------------------- files


_SafeLoader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when installed


class _UniqueKeyLoader(_SafeLoader):
    """The safe loader, refusing a mapping that gives a key twice (the first would be lost)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = self.construct_object(key_node, deep=deep)
            try:
                first = seen.setdefault(key, key_node.start_mark.line)
            except TypeError:  # an unhashable key: the constructor says so below
                continue
            if first != key_node.start_mark.line:
                raise yaml.constructor.ConstructorError(
                    None,
                    None,
                    f"duplicate key {key!r} (first on line {first + 1})",
                    key_node.start_mark,
                )
        return super().construct_mapping(node, deep)


def _yaml_reason(exc: yaml.YAMLError) -> str:
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    return f"{one_line(problem)}{where}"


def read_yaml_mapping(path: str | Path, what: str) -> dict[Any, Any]:
    """The mapping at the top of the YAML file ``path``, a ``what`` file (e.g. "scenario").

    Raises
    ------
    FileFormatError
        The file is binary (a NUL byte: a Parquet log, say), not UTF-8 text,
        not valid YAML, gives a key twice, or holds anything but a mapping.
    OSError
        The file cannot be read (``FileNotFoundError``, ``IsADirectoryError``...).
    """
    path = Path(path)
    raw = path.read_bytes()
    if raw.startswith(b"PAR1"):
        raise FileFormatError(f"{path} is a Parquet file (a log?), not a YAML {what} file")
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise FileFormatError(
            f"{path} is a binary file (NUL byte at offset {nul}), not a YAML {what} file"
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(
            f"{path} is not UTF-8 text (byte {exc.start}), not a YAML {what} file"
        ) from None
    try:
        data = yaml.load(text, Loader=_UniqueKeyLoader)  # a SafeLoader that refuses duplicates
    except yaml.YAMLError as exc:
        raise FileFormatError(f"{path} is not valid YAML: {_yaml_reason(exc)}") from None
    if not isinstance(data, dict):
        got = "an empty file" if data is None else shown(data)
        raise FileFormatError(
            f"{path}: a {what} file holds a YAML mapping (key: value lines); got {got}"
        )
    return data


def check_format_version(data: Mapping[Any, Any], current: int, source: str, what: str) -> None:
    """Refuse a ``format_version`` newer than ``current`` (absent: the current one).

    Other wrong values (text, 0) are left to the file's model, which says what
    it expects.
    """
    version = data.get("format_version", current)
    if _is_number(version) and isinstance(version, int) and version > current:
        raise FileFormatError(
            f"{source}: format_version {version} is newer than the {what} format this "
            f"sensorless ({__version__}) reads (version {current}); upgrade sensorless or "
            f"write a version-{current} file"
        )
