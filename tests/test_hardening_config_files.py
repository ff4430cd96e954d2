"""Configuration files that used to load wrongly or fail unclearly.

- a boolean for a numeric field (TOML ``true``, YAML ``yes``/``on``, JSON ``true``) gave 1;
- a key given twice in a JSON object or a YAML mapping silently kept the last value;
- a UTF-8 file with a byte-order mark failed to parse; a latin-1 file failed without its name;
- a YAML key that is not text (``1:``) ended in a comparison error.

Each is now a ``ValueError`` naming the file and the field or key (a BOM'd UTF-8 file loads).
The property tests check the mechanism, not a list of inputs: any numeric field of any class
refuses any boolean; the strict JSON/YAML readers give exactly the standard readers' result on
any document without repeated keys, and refuse any document with one.
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scas_env.actuator.config import param
from scas_env.actuator.params import ScasParams
from scas_env.core.costs import CostModel
from scas_env.core.scenario import Scenario
from scas_env.utils.config_files import read_mapping
from tests.config_cases import CLASSES, numeric_fields

SETTINGS = settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
NUMERIC = [
    (cls, name)
    for cls in CLASSES
    for name, md in numeric_fields(cls).items()
    if md["unit"] != "bool"  # a switch (0/1) takes true/false
]
SWITCHES = [
    (cls, name)
    for cls in CLASSES
    for name, md in numeric_fields(cls).items()
    if md["unit"] == "bool"
]


# --- booleans for numbers --------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("a.toml", "episode_slots = true\n"),
        ("a.yaml", "episode_slots: yes\n"),
        ("a.yml", "episode_slots: on\n"),
        ("a.yaml", "episode_slots: false\n"),
        ("a.json", '{"episode_slots": true}'),
        ("a.toml", "[scenario]\nepisode_slots = true\n"),
    ],
)
def test_a_boolean_for_a_number_is_refused_naming_file_and_field(
    tmp_path: Path, name: str, text: str
) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError) as err:
        Scenario.load(path)
    message = str(err.value)
    assert str(path) in message and "Scenario.episode_slots" in message
    assert "is a boolean; expected a number in [1, 1e+07] slots" in message


def test_a_boolean_in_a_nested_params_table_names_the_table(tmp_path: Path) -> None:
    path = tmp_path / "p.yaml"
    path.write_text("params:\n  spring:\n    paris_m: yes\n")
    with pytest.raises(ValueError, match=r"p\.yaml \[params\.spring\]: SpringParams\.paris_m = "
                       r"True is a boolean; expected a number"):  # fmt: skip
        ScasParams.load(path)


@SETTINGS
@given(
    pick=st.sampled_from(NUMERIC),
    flag=st.sampled_from([True, False, np.True_, np.False_]),
)
def test_every_numeric_field_refuses_every_boolean(pick: tuple[type, str], flag: Any) -> None:
    cls, name = pick
    with pytest.raises(ValueError, match=rf"{cls.__name__}\.{name} = \S+ is a boolean"):
        cls.from_dict({name: flag})


@pytest.mark.parametrize(
    ("name", "text", "expected"),
    [
        ("s.toml", "crack_active = false\n", 0),
        ("s.yaml", "crack_active: no\n", 0),
        ("s.yml", "crack_active: yes\n", 1),
        ("s.json", '{"crack_active": false}', 0),
        ("s.toml", "crack_active = 0\n", 0),
    ],
)
def test_switches_take_booleans_as_0_and_1(
    tmp_path: Path, name: str, text: str, expected: int
) -> None:
    """A switch is declared with unit "bool" (0/1): there true/false is the natural input."""
    path = tmp_path / name
    path.write_text(text)
    value = Scenario.load(path).crack_active
    assert value == expected and type(value) is int


@SETTINGS
@given(pick=st.sampled_from(SWITCHES), flag=st.sampled_from([True, False, np.True_, np.False_]))
def test_every_switch_takes_every_boolean(pick: tuple[type, str], flag: Any) -> None:
    cls, name = pick
    data = {name: flag}
    if cls is Scenario and not flag:  # a cross-field rule: one fault stays on
        data["wear_active" if name == "crack_active" else "crack_active"] = 1
    assert getattr(cls.from_dict(data), name) == int(flag)


def test_every_class_declares_its_switches_with_the_bool_unit() -> None:
    assert (Scenario, "crack_active") in SWITCHES and (Scenario, "wear_active") in SWITCHES
    with pytest.raises(ValueError, match=r"a switch \(unit 'bool'\) is an integer in \[0, 1\]"):
        param(1, "bool", lo=0, hi=2, integer=True)


# --- keys given twice ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "text", "key"),
    [
        ("d.json", '{"episode_slots": 5, "episode_slots": 7}', "episode_slots"),
        ("d.json", '{"costs": {"test_usd": 1, "test_usd": 2}}', "test_usd"),
        ("d.yaml", "episode_slots: 5\nepisode_slots: 7\n", "episode_slots"),
        ("d.yaml", "{episode_slots: 5, episode_slots: 7}\n", "episode_slots"),
        ("d.yml", "costs:\n  test_usd: 1\n  test_usd: 2\n", "test_usd"),
        ("d.yaml", "scenario: {}\nscenario: {}\n", "scenario"),
        ("d.toml", "episode_slots = 5\nepisode_slots = 7\n", "episode_slots"),
    ],
)
def test_a_key_given_twice_is_refused_naming_file_and_key(
    tmp_path: Path, name: str, text: str, key: str
) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError) as err:
        read_mapping(path)
    message = str(err.value)
    assert message.startswith(f"{path}: ")
    if path.suffix != ".toml":  # tomllib's own message: "Cannot overwrite a value (at ...)"
        assert f"key {key!r} appears twice" in message


def test_yaml_merge_keys_still_override_what_they_merge(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("base: &b {test_usd: 1.0, labour_usd_per_h: 2.0}\ncosts:\n  <<: *b\n"
                    "  test_usd: 3.0\n")  # fmt: skip
    assert read_mapping(path)["costs"] == {"test_usd": 3.0, "labour_usd_per_h": 2.0}


#: letters of any script, digits, spaces, dashes, underscores: text both parsers read alike
#: in any quoting (YAML folds raw line breaks and refuses some code points; JSON escapes them)
words = st.text(st.characters(categories=["L", "N", "Pd", "Pc", "Zs"]), max_size=8)
keys = words
scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=False, allow_infinity=False),
    words,
)
documents = st.recursive(
    st.dictionaries(keys, scalars, max_size=4),
    lambda inner: st.dictionaries(
        keys, st.one_of(scalars, inner, st.lists(inner, max_size=2)), max_size=4
    ),
    max_leaves=12,
)


@SETTINGS
@given(doc=documents, bom=st.booleans())
def test_strict_readers_agree_with_the_standard_ones(tmp_path: Path, doc: dict, bom: bool) -> None:
    """Without repeated keys the strict JSON and YAML readers change nothing (BOM or not)."""
    prefix = b"\xef\xbb\xbf" if bom else b""
    for name, text in (
        ("doc.json", json.dumps(doc)),
        ("doc.yaml", yaml.safe_dump(doc, allow_unicode=True)),
    ):
        path = tmp_path / name
        path.write_bytes(prefix + text.encode("utf-8"))
        expected = json.loads(text) if name.endswith("json") else yaml.safe_load(text)
        assert read_mapping(path) == expected


@SETTINGS
@given(doc=st.dictionaries(keys, scalars, min_size=1, max_size=5), data=st.data())
def test_any_repeated_key_is_refused(tmp_path: Path, doc: dict, data: Any) -> None:
    """A key repeated anywhere in an object (JSON) or a mapping (YAML, block and flow)."""
    key = data.draw(st.sampled_from(sorted(doc)))
    value = data.draw(scalars)
    items = [(k, v) for k, v in doc.items()]
    items.insert(data.draw(st.integers(0, len(items))), (key, value))
    json_text = "{" + ", ".join(f"{_json(k)}: {_json(v)}" for k, v in items) + "}"
    nested = data.draw(st.booleans())
    if nested:
        json_text = '{"outer": [' + json_text + "]}"
    path = tmp_path / "dup.json"
    path.write_text(json_text, encoding="utf-8")
    with pytest.raises(ValueError, match=re.escape(f"{path}: key {key!r} appears twice")):
        read_mapping(path)
    yaml_text = json_text if data.draw(st.booleans()) else _yaml_block(items)
    path = tmp_path / "dup.yaml"
    path.write_text(yaml_text, encoding="utf-8")
    with pytest.raises(ValueError, match=re.escape(f"{path}: key {key!r} appears twice")):
        read_mapping(path)


def _json(value: Any) -> str:
    return json.dumps(value, ensure_ascii=False)


def _yaml_block(items: list[tuple[str, Any]]) -> str:
    """A block mapping with the items in order (repeats kept), each pair dumped by PyYAML."""
    return "".join(yaml.safe_dump({k: v}, allow_unicode=True, width=10**6) for k, v in items)


# --- encodings -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("b.toml", "# cost\nepisode_slots = 12\n"),
        ("b.yaml", "# cost\nepisode_slots: 12\n"),
        ("b.json", '{"episode_slots": 12}'),
    ],
)
def test_a_utf8_file_with_a_byte_order_mark_loads(tmp_path: Path, name: str, text: str) -> None:
    path = tmp_path / name
    path.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    assert Scenario.load(path).episode_slots == 12


@pytest.mark.parametrize("suffix", [".toml", ".yaml", ".json"])
@pytest.mark.parametrize("encoding", ["latin-1", "utf-16", "cp1252"])
def test_a_file_not_in_utf8_is_one_clear_error(tmp_path: Path, suffix: str, encoding: str) -> None:
    path = tmp_path / f"enc{suffix}"
    body = {
        ".toml": "# café\nepisode_slots = 12\n",
        ".yaml": "# café\nepisode_slots: 12\n",
        ".json": '{"episode_slots": 12, "note": "café"}',
    }[suffix]
    path.write_bytes(body.encode(encoding))
    with pytest.raises(ValueError) as err:
        Scenario.load(path)
    message = str(err.value)
    assert message.startswith(f"{path}: not UTF-8 text (byte 0x")
    assert "configuration files must be encoded as UTF-8" in message
    assert err.value.__cause__ is None and err.value.__suppress_context__


def test_a_key_that_is_not_text_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "k.yaml"
    path.write_text("costs:\n  1: 2\n")
    with pytest.raises(ValueError, match=r"k\.yaml \[costs\]: key 1 \(int\) is not a name"):
        CostModel.load(path)
    path.write_text("yes: 2\n")
    with pytest.raises(ValueError, match=r"k\.yaml: key True \(bool\) is not a name"):
        Scenario.load(path)


def test_mixed_unknown_keys_are_listed_not_compared() -> None:
    with pytest.raises(ValueError, match=r"Scenario: unknown key\(s\) \['a', 1\]"):
        Scenario.from_dict({1: 2, "a": 3})


def test_every_class_is_covered() -> None:
    assert {c.__name__ for c in CLASSES} >= {"Scenario", "CostModel", "SpringParams"}
    assert all(dataclasses.is_dataclass(c) for c in CLASSES)
