"""Scene tables written back as TOML text: :mod:`tomllib` the other way round.

Python reads TOML but does not write it, and fretwork depends on no TOML writer. A scene's
tables hold only what TOML gives (tables, arrays, strings, integers, floats, booleans, dates and
times), and this writer covers all of them: ``tomllib.loads(dumps(tables)) == tables`` (fuzzed
in ``tests/pipelines/test_resolved_scene.py``). Tables are written as ``[a.b]`` headers and
arrays of tables as ``[[a]]``, in the tables' own key order; anything inside an array is written
inline. Comments and layout of the files the tables came from are not kept.
"""

from __future__ import annotations

import datetime
import json
import math
import re

BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def dumps(tables: dict) -> str:
    """TOML text of ``tables`` (a dict as :func:`tomllib.loads` returns)."""
    lines: list[str] = []
    _write_table(tables, (), lines, array_entry=False)
    return "\n".join(lines).lstrip("\n") + "\n"


def _is_array_of_tables(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(entry, dict) for entry in value)


def _write_table(table: dict, header: tuple, lines: list, array_entry: bool) -> None:
    values = [(key, value) for key, value in table.items()
              if not isinstance(value, dict) and not _is_array_of_tables(value)]
    # a table with only tables below it needs no header of its own (TOML defines it implicitly)
    if array_entry or (header and (values or not table)):
        lines += ["", f"[[{_dotted(header)}]]" if array_entry else f"[{_dotted(header)}]"]
    lines += [f"{_key(key)} = {_value(value)}" for key, value in values]
    for key, value in table.items():
        if isinstance(value, dict):
            _write_table(value, header + (key,), lines, array_entry=False)
        elif _is_array_of_tables(value):
            for entry in value:
                _write_table(entry, header + (key,), lines, array_entry=True)


def _dotted(keys: tuple) -> str:
    return ".".join(_key(key) for key in keys)


def _key(key: str) -> str:
    return key if BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    # JSON's escapes (\" \\ \n \uXXXX ...) are TOML's too; TOML also wants DEL escaped
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, (datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(_value(entry) for entry in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(key)} = {_value(entry)}" for key, entry in value.items()) + "}"
    raise TypeError(f"no TOML for {type(value).__name__} {value!r}")
