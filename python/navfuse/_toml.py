"""A small TOML writer for configuration dicts (``navfuse.run({...})``): tables,
arrays of tables, strings, numbers, booleans and arrays of them."""

from __future__ import annotations

import math
import os
import re
from typing import Any, Dict, List

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def _key(k: str) -> str:
    return k if _BARE_KEY.fullmatch(k) else _str(k)


def _str(s: str) -> str:
    out = "".join(_ESCAPES.get(c) or (f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F else c)
                  for c in s)
    return f'"{out}"'


def _value(v: Any, where: str) -> str:
    if type(v).__module__ == "numpy":  # NumPy scalars and arrays: Python values first
        v = v.tolist()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        if not -(2**63) <= v < 2**63:
            raise ValueError(f"config key {where}: {v} is outside TOML's 64-bit integers")
        return str(int(v))
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"config key {where}: {v} is not a finite number")
        return repr(float(v))
    if isinstance(v, (str, os.PathLike)):
        return _str(os.fspath(v))
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, where) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x, where + '.' + k)}" for k, x in v.items()) + " }"
    raise TypeError(f"config key {where}: cannot write a {type(v).__name__} as TOML")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def dumps(d: Dict[str, Any]) -> str:
    lines: List[str] = []

    def table(t: Dict[str, Any], path: List[str]) -> None:
        subs = []
        for k, v in t.items():
            if not isinstance(k, str):
                raise TypeError(f"config keys must be strings, found {k!r}")
            if v is None:
                continue
            if isinstance(v, dict) or _is_table_array(v):
                subs.append((k, v))
            else:
                lines.append(f"{_key(k)} = {_value(v, '.'.join(path + [k]))}")
        for k, v in subs:
            p = path + [k]
            name = ".".join(_key(x) for x in p)
            if isinstance(v, dict):
                lines.append(f"\n[{name}]")
                table(v, p)
            else:
                for item in v:
                    lines.append(f"\n[[{name}]]")
                    table(item, p)

    table(d, [])
    return "\n".join(lines).lstrip("\n") + "\n"
