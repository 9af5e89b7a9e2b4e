"""Reading user-written YAML and turning pydantic errors into one line: shared by params.yaml and terrain files.

`read_yaml` refuses duplicate keys (PyYAML would silently keep the last) and reports syntax errors with their line;
`format_validation_error` names the first bad key as the user wrote it (e.g. `boxes[1].size`), what was given and
what is allowed. Both raise or return text for the caller's own error class (ConfigError, TerrainError).
"""

from __future__ import annotations

import math
import types
import typing
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses a mapping with the same key twice."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if isinstance(key, typing.Hashable) and key in seen:
                raise _DuplicateKey(key, key_node.start_mark.line + 1)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


class _DuplicateKey(Exception):
    def __init__(self, key: Any, line: int):
        super().__init__(key, line)
        self.key, self.line = key, line


def parse_yaml(text: str, source: str, error: type[Exception]) -> Any:
    """YAML text -> Python data (safe subset, no duplicate keys); `error(one line naming source)` otherwise."""
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # a SafeLoader subclass: no arbitrary objects
    except _DuplicateKey as dup:
        raise error(f"{source}: line {dup.line}: duplicate key '{dup.key}' (each key may appear once)") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" line {mark.line + 1}:" if mark else ""
        problem = " ".join(str(getattr(exc, "problem", None) or exc).split())
        raise error(f"{source}:{where} not valid YAML ({problem})") from None


def read_yaml(path: Path, error: type[Exception], source: str | None = None) -> Any:
    """Read and parse a YAML file; unreadable or malformed files raise `error` with one line."""
    source = source or str(path)
    try:
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc.__class__.__name__
        raise error(f"{source}: cannot read ({reason})") from None
    return parse_yaml(text, source, error)


def one_line(exc: BaseException) -> str:
    """An exception as one line, type first, for messages that wrap a library's error."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def show(value: Any) -> str:
    """A user-facing rendering of a value: tuples as YAML-like lists."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(show(v) for v in value) + "]"
    if isinstance(value, float) and not math.isfinite(value):
        return {math.inf: ".inf", -math.inf: "-.inf"}.get(value, ".nan")
    return repr(value)


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    """Every BaseModel class reachable through an annotation (unions, tuples, Annotated, Optional)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    for arg in typing.get_args(annotation):
        found += _models_in(arg)
    return found


def _allows(annotation: Any, kind: type) -> bool:
    if annotation is kind:
        return True
    if isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is not None:
        return any(_allows(a, kind) for a in typing.get_args(annotation))
    return False


def bool_misused(annotation: Any, value: Any) -> bool:
    """True when a YAML boolean is given where a field of this annotation wants numbers or text.

    pydantic's lax mode reads `true` as 1; a field that does not name bool (anywhere in its annotation) refuses it,
    alone, in a list or as a mapping's value. Sub-sections (models) check their own fields.
    """
    if _allows(annotation, bool) or _models_in(annotation):
        return False
    items = value.values() if isinstance(value, dict) else value if isinstance(value, list | tuple) else [value]
    return any(isinstance(v, bool) for v in items)


def format_validation_error(
    exc: ValidationError, model: type[BaseModel], source: str, tags: dict[str, type[BaseModel]] | None = None
) -> str:
    """One line: source, the entry path as the user wrote it (`boxes[1].size`), what is wrong and what was given.

    `tags` maps discriminated-union tags (which pydantic puts in the location) to their models, so that an unknown
    key inside such an entry lists the keys allowed there.
    """
    tags = tags or {}
    err = exc.errors()[0]
    loc = tuple(err["loc"])
    parts: list[str] = []
    current: type[BaseModel] | None = model
    owner: type[BaseModel] | None = model  # the model whose keys are listed for an unknown key
    for i, part in enumerate(loc):
        if isinstance(part, int):
            if parts:
                parts[-1] += f"[{part}]"
            else:
                parts.append(f"[{part}]")
            continue
        if i > 0 and isinstance(loc[i - 1], int) and part in tags:
            current = tags[part]  # the discriminator's tag, not a key the user wrote
            continue
        parts.append(str(part))
        owner = current
        field = current.model_fields.get(str(part)) if current is not None else None
        candidates = _models_in(field.annotation) if field is not None else []
        current = candidates[0] if len(candidates) == 1 else None
    key = ".".join(parts)
    if err["type"] == "extra_forbidden":
        allowed = ", ".join(sorted(owner.model_fields)) if owner is not None else "(see the docs)"
        return f"{source}: unknown key '{key}'; allowed here: {allowed}"
    where = f"{key}: " if key else ""
    if err["type"] == "value_error":
        return f"{source}: {where}{err['ctx']['error']}"
    given = err.get("input")
    if err["type"] in ("model_type", "dict_type", "model_attributes_type"):
        return f"{source}: {where}expected a mapping of keys, got {show(given)}"
    if err["type"] in ("tuple_type", "list_type"):
        return f"{source}: {where}expected a list, got {show(given)}"
    shown = "" if isinstance(given, dict) or err["type"] == "missing" else f" (got {show(given)})"
    return f"{source}: {where}{err['msg']}{shown}"
