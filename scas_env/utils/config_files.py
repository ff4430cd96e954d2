"""Configuration files: TOML, YAML or JSON mappings by suffix, read and written checked.

Files are UTF-8 (a byte-order mark is allowed); a key may appear once per mapping. Readers:
:mod:`tomllib`, PyYAML's ``SafeLoader`` (no object construction, so a file cannot run code)
and :mod:`json`, the last two refusing a repeated key (:func:`read_mapping`). Writers: a small
TOML writer for such mappings (:func:`toml_text`), PyYAML's ``safe_dump`` and :mod:`json`.
Files are written atomically (a temporary file renamed into place); an existing file is
refused unless ``overwrite=True``. The validated groups that such files describe are
:class:`~scas_env.actuator.config.Validated`.

Example:
    >>> print(toml_text({"scenario": {"episode_slots": 500}, "costs": {"test_usd": 100.0}}))
    [scenario]
    episode_slots = 500
    <BLANKLINE>
    [costs]
    test_usd = 100.0
    <BLANKLINE>
"""

from __future__ import annotations

import json
import math
import re
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from scas_env.utils.atomic_file import refuse_existing, write_text_atomic

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10: the tomli backport (a declared dependency there)
    import tomli as tomllib

#: File suffix -> format name.
FORMATS = {".toml": "toml", ".yaml": "yaml", ".yml": "yaml", ".json": "json"}
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def file_format(path: str | Path) -> str:
    """Format name (``"toml"``, ``"yaml"`` or ``"json"``) from the suffix of ``path``."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(
            f"{path}: unknown configuration file type {suffix!r}; "
            f"allowed suffixes: {sorted(FORMATS)}"
        )
    return FORMATS[suffix]


def read_mapping(path: str | Path) -> dict[str, Any]:
    """Parse ``path`` (TOML, YAML or JSON by suffix) into a dict.

    The file must be UTF-8 text (a leading UTF-8 byte-order mark is allowed and ignored).
    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` naming the file for
    text that is not UTF-8, a syntax error, a key given twice in one mapping (TOML refuses
    it itself; JSON and YAML parsers would keep the last value), a key that is not text, or a
    document that is not a mapping (an empty YAML file is ``{}``).
    """
    path = Path(path)
    kind = file_format(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: configuration file not found")
    text = _read_text(path)
    try:
        if kind == "toml":
            data: Any = tomllib.loads(text)
        elif kind == "yaml":
            data = _yaml_load(text)
            data = {} if data is None else data
        else:
            data = json.loads(text, object_pairs_hook=_json_object)
    except _DuplicateKeyError as exc:
        raise ValueError(f"{path}: {exc}") from None
    except Exception as exc:  # each parser has its own error class; all mean "bad syntax"
        raise ValueError(f"{path}: not valid {kind.upper()}: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(
            f"{path}: expected a mapping of field names to values, got {type(data).__name__}"
        )
    _check_keys(data, path, ())
    return data


def _read_text(path: Path) -> str:
    """The file's text, decoded as UTF-8 (a leading byte-order mark dropped)."""
    raw = path.read_bytes()
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise ValueError(
            f"{path}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}, "
            f"line {line}); configuration files must be encoded as UTF-8 "
            "(re-save it as UTF-8, e.g. `iconv -f latin1 -t utf-8`)"
        ) from None


class _DuplicateKeyError(ValueError):
    """A key given twice in one mapping of a JSON or YAML document."""


def _json_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``object_pairs_hook`` of :func:`json.loads`: a dict, refusing a repeated key."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKeyError(
                f"key {key!r} appears twice in one object; each key may be given once"
            )
        out[key] = value
    return out


def _yaml_load(text: str) -> Any:
    """``yaml.safe_load`` that refuses a key given twice in one mapping (PyYAML keeps the
    last one). Merge keys (``<<: *base``) still override what they merge, as YAML defines."""
    import yaml

    global _StrictYamlLoader
    if _StrictYamlLoader is None:

        class StrictLoader(yaml.SafeLoader):
            def construct_mapping(self, node: Any, deep: bool = False) -> Any:
                if isinstance(node, yaml.MappingNode):
                    seen: dict[Any, int] = {}
                    for key_node, _ in node.value:
                        if key_node.tag == "tag:yaml.org,2002:merge":
                            continue
                        key = self.construct_object(key_node, deep=True)
                        line = key_node.start_mark.line + 1
                        try:
                            first = seen.get(key)
                        except TypeError:  # unhashable: PyYAML's own error follows
                            continue
                        if first is not None:
                            raise _DuplicateKeyError(
                                f"key {key!r} appears twice in one mapping (lines {first} "
                                f"and {line}); each key may be given once"
                            )
                        seen[key] = line
                return super().construct_mapping(node, deep=deep)

        _StrictYamlLoader = StrictLoader
    return yaml.load(text, Loader=_StrictYamlLoader)  # a SafeLoader subclass: no objects


_StrictYamlLoader: Any = None


def _check_keys(data: Mapping[Any, Any], path: Path, where: tuple[str, ...]) -> None:
    """Every key of every nested mapping is text (YAML allows ``1:`` or ``yes:`` as keys)."""
    for key, value in data.items():
        if not isinstance(key, str):
            table = f" [{'.'.join(where)}]" if where else ""
            raise ValueError(
                f"{path}{table}: key {key!r} ({type(key).__name__}) is not a name; "
                "keys are field or table names (text)"
            )
        if isinstance(value, Mapping):
            _check_keys(value, path, (*where, key))


def write_mapping(path: str | Path, data: Mapping[str, Any], *, overwrite: bool = False) -> Path:
    """Write ``data`` to ``path`` in the format of its suffix, atomically; returns the path.

    An existing file raises ``FileExistsError`` unless ``overwrite``; the folder must exist.
    """
    path = Path(path)
    kind = file_format(path)
    refuse_existing(path, overwrite)
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path}: folder {path.parent} does not exist")
    if kind == "toml":
        text = toml_text(data)
    elif kind == "yaml":
        import yaml

        text = yaml.safe_dump(_plain(data), sort_keys=False, allow_unicode=True)
    else:
        text = json.dumps(_plain(data), indent=2) + "\n"
    write_text_atomic(path, text)
    return path


def _plain(data: Any) -> Any:
    """Tuples -> lists, recursively (YAML's safe dumper and TOML know lists only)."""
    if isinstance(data, Mapping):
        return {str(k): _plain(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [_plain(v) for v in data]
    return data


def toml_text(data: Mapping[str, Any]) -> str:
    """TOML document of a nested mapping of str, bool, int, finite float and lists of them.

    Scalars of a table come before its sub-tables (``[a]``, ``[a.b]``), as TOML requires.
    Floats are written with :func:`repr`, which round-trips exactly. ``None`` and non-finite
    floats raise ``ValueError`` (TOML has no null; configurations are finite).
    """
    lines: list[str] = []
    _toml_table(data, (), lines)
    return "\n".join(lines).lstrip("\n") + "\n"


def _toml_table(data: Mapping[str, Any], prefix: tuple[str, ...], lines: list[str]) -> None:
    tables = {k: v for k, v in data.items() if isinstance(v, Mapping)}
    if prefix and (len(tables) < len(data) or not data):
        lines.append(f"\n[{'.'.join(_toml_key(p) for p in prefix)}]")
    for key, value in data.items():
        if key not in tables:
            lines.append(f"{_toml_key(key)} = {_toml_value(value, (*prefix, key))}")
    for key, value in tables.items():
        _toml_table(value, (*prefix, str(key)), lines)


def _toml_key(key: Any) -> str:
    key = str(key)
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_string(text: str) -> str:
    """TOML basic string: backslash, quote and control characters escaped."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_value(value: Any, where: tuple[str, ...]) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{'.'.join(where)} = {value} cannot be written: not finite")
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v, where) for v in value) + "]"
    raise ValueError(
        f"{'.'.join(where)} = {value!r} cannot be written to TOML "
        f"(allowed: str, bool, int, finite float, lists and tables of them)"
    )
