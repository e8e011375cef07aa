"""Validates plain YAML data against a dataclass schema before Drake's typed loader sees it.

`pydrake.common.yaml.yaml_load_typed` rejects unknown keys and wrong types, but its messages
do not say which nested field is wrong. This walks the data alongside the schema and raises
one error that names the file and the full field path (for example
`scenarios/default.yaml: scene[2].position: expected a list of numbers, got 'left'`).
"""

import dataclasses
import math
import types
import typing
from typing import Any

_NUMBER_TYPES = (int, float)


def _describe(value: Any) -> str:
    text = repr(value)
    return text if len(text) < 80 else text[:77] + "..."


def check_against_schema(data: Any, schema: Any, path: str, where: str, error_type: type[Exception]) -> None:
    """Raises `error_type("<where>: <path>: <problem>")` at the first mismatch of `data` and `schema`."""

    def fail(problem: str) -> typing.NoReturn:
        field = f" {path}:" if path else ""
        raise error_type(f"{where}:{field} {problem}")

    origin = typing.get_origin(schema)
    if origin in (typing.Union, types.UnionType):
        options = typing.get_args(schema)
        if data is None and type(None) in options:
            return
        candidates = [option for option in options if option is not type(None)]
        first_error = None
        for option in candidates:
            try:
                check_against_schema(data, option, path, where, error_type)
                return
            except error_type as error:
                first_error = first_error or error
        if first_error is not None:
            raise first_error
        fail(f"unexpected value {_describe(data)}")
    if dataclasses.is_dataclass(schema):
        if not isinstance(data, dict):
            fail(f"expected a mapping of the fields of {schema.__name__}, got {_describe(data)}")
        fields = {f.name: f for f in dataclasses.fields(schema)}
        hints = typing.get_type_hints(schema)
        for key, value in data.items():
            field_path = f"{path}.{key}" if path else str(key)
            if key not in fields:
                allowed = ", ".join(sorted(fields))
                raise error_type(f"{where}: {field_path}: unknown field; {schema.__name__} has: {allowed}")
            check_against_schema(value, hints[key], field_path, where, error_type)
        return
    drake_fields = getattr(schema, "__fields__", None)
    if drake_fields is not None:
        # pydrake's own config structs (MultibodyPlantConfig, DrakeLcmParams, ...).
        if not isinstance(data, dict):
            fail(f"expected a mapping of the fields of {schema.__name__}, got {_describe(data)}")
        field_types = {f.name: f.type for f in drake_fields}
        for key, value in data.items():
            field_path = f"{path}.{key}" if path else str(key)
            if key not in field_types:
                allowed = ", ".join(sorted(field_types))
                raise error_type(f"{where}: {field_path}: unknown field; {schema.__name__} has: {allowed}")
            check_against_schema(value, field_types[key], field_path, where, error_type)
        return
    if origin is list:
        (item_type,) = typing.get_args(schema) or (Any,)
        if not isinstance(data, list):
            fail(f"expected a list, got {_describe(data)}")
        for i, item in enumerate(data):
            check_against_schema(item, item_type, f"{path}[{i}]", where, error_type)
        return
    if origin is dict:
        key_type, value_type = typing.get_args(schema) or (Any, Any)
        if not isinstance(data, dict):
            fail(f"expected a mapping, got {_describe(data)}")
        for key, value in data.items():
            check_against_schema(value, value_type, f"{path}[{key!r}]", where, error_type)
        return
    if schema is float:
        if isinstance(data, bool) or not isinstance(data, _NUMBER_TYPES):
            fail(f"expected a number, got {_describe(data)}")
        if not math.isfinite(float(data)):
            fail(f"expected a finite number, got {_describe(data)}")
        return
    if schema is int:
        if isinstance(data, bool) or not isinstance(data, int):
            fail(f"expected an integer, got {_describe(data)}")
        return
    if schema is bool:
        if not isinstance(data, bool):
            fail(f"expected true or false, got {_describe(data)}")
        return
    if schema is str:
        if not isinstance(data, str):
            fail(f"expected a string, got {_describe(data)}")
        return
    # Drake's own config structs (MultibodyPlantConfig, ...) and Any: leave to yaml_load_typed.
