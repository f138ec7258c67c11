"""The dataclasses of fieldhouse.messages against the schemas in proto/, and the error
classes against PROTOCOL.md's tables: a protocol change this package misses fails here."""

from __future__ import annotations

import dataclasses
import json
import re

import jsonschema
import pytest

from fieldhouse import errors, messages
from fieldhouse.messages import Accelerate, MoveTo, Pass, RunTo, Shoot, Stand, encode_command

from .conftest import REPO

PROTO = REPO / "proto"

# Each dataclass and the schema object it mirrors: (file, $defs name or None for the root).
MIRRORS = [
    (messages.Hello, "hello", None),
    (messages.MatchInfo, "hello", "MatchInfo"),
    (messages.AgentInfo, "hello", "AgentInfo"),
    (messages.Limits, "hello", "Limits"),
    (messages.Perception, "perception", None),
    (messages.FielderPerception, "perception", "FielderPerception"),
    (messages.Optics, "perception", "Optics"),
    (messages.Rates, "perception", "Rates"),
    (messages.SelfSensed, "perception", "SelfSensed"),
    (messages.BodyLimits, "perception", "BodyLimits"),
    (messages.PlayerPerception, "perception", "PlayerPerception"),
    (messages.SeenPlayer, "perception", "SeenPlayer"),
    (messages.HoopsBall, "perception", "HoopsBall"),
    (messages.End, "end", None),
    (messages.ErrorMessage, "error", None),
]


def schema(name: str) -> dict:
    return json.loads((PROTO / f"{name}.schema.json").read_text())


def wire_names(cls) -> set[str]:
    return {f.metadata.get("wire", f.name) for f in dataclasses.fields(cls)}


def schema_object(name: str, definition: str | None) -> dict:
    s = schema(name)
    if definition is None:
        return s
    defs = s["$defs"]
    if definition not in defs:
        pytest.fail(f"{name}.schema.json has no $defs.{definition}; it has {sorted(defs)}")
    obj = defs[definition]
    if "anyOf" in obj:
        # A union by sport (AgentInfo: fielder or player): one class holds every variant's
        # fields, and requires what they all require.
        variants = [defs[v["$ref"].rsplit("/", 1)[1]] for v in obj["anyOf"]]
        required = set.intersection(*(set(v.get("required", ())) for v in variants))
        properties = {k: p for v in variants for k, p in v["properties"].items()}
        return {"properties": properties, "required": sorted(required)}
    return obj


@pytest.mark.parametrize(
    ("cls", "name", "definition"), MIRRORS, ids=lambda v: getattr(v, "__name__", v)
)
def test_dataclass_fields_are_the_schemas_properties(cls, name, definition):
    obj = schema_object(name, definition)
    properties = set(obj["properties"]) - {"type"}
    assert wire_names(cls) == properties
    # A field without a default is one the schema requires (decoding demands it).
    required = set(obj.get("required", ())) - {"type"}
    demanded = {
        f.metadata.get("wire", f.name)
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }
    assert demanded <= required


def action_variants() -> dict[str, set[str]]:
    variants = schema("command")["$defs"]["Action"]["oneOf"]
    return {v["properties"]["kind"]["const"]: set(v["properties"]) for v in variants}


def test_every_action_kind_has_a_class_with_its_fields():
    by_kind = {cls.kind: cls for cls in messages.ACTIONS}
    variants = action_variants()
    assert set(by_kind) == set(variants)
    for kind, props in variants.items():
        assert wire_names(by_kind[kind]) | {"kind"} == props, kind


@pytest.mark.parametrize(
    "action",
    [Accelerate((1, -2.5)), RunTo((61.2, 20.4)), MoveTo((3.0, -1)), Pass("o2"), Shoot(), Stand()],
    ids=lambda a: a.kind,
)
def test_encoded_commands_validate_against_the_schema(action):
    command = json.loads(encode_command(7, action))
    jsonschema.validate(command, schema("command"))
    assert command["tick"] == 7 and isinstance(command["tick"], int)


def test_protocol_examples_decode():
    # The perception examples of PROTOCOL.md, decoded into their classes.
    text = (REPO / "PROTOCOL.md").read_text()
    block = re.search(r'```json\n(\{"type": "perception".*?)\n```', text, re.S).group(1)
    p = messages.parse(block)
    assert isinstance(p.perception, messages.FielderPerception)
    assert p.perception.body.home == p.perception.body.position
    assert p.perception.optics is None and p.perception.limits.max_speed_m_s == 8.5


def protocol_error_codes() -> set[str]:
    """The codes of PROTOCOL.md's two error tables (REST and `error` messages) and the
    HTTP layer's paragraph after the first."""
    text = (REPO / "PROTOCOL.md").read_text()
    rest = re.findall(r"^\| \d{3} \| `([a-z_]+)` \|", text, re.M)
    table = text.split("| `code` | Meaning |", 1)[1].split("\n\n", 1)[0]
    ws = re.findall(r"^\| `([a-z_]+)` \|", table, re.M)
    layer = re.search(r"Errors of the HTTP layer are JSON too:(.*?)\n\n", text, re.S).group(1)
    return set(rest) | set(ws) | set(re.findall(r"\d{3} `([a-z_]+)`", layer))


def test_every_error_code_in_protocol_md_has_its_exception():
    codes = protocol_error_codes()
    assert {"bad_scenario", "rejected", "stale_tick", "too_large", "replaced"} <= codes
    missing = codes - set(errors.ERRORS_BY_CODE)
    assert not missing, f"PROTOCOL.md lists codes without an exception class: {sorted(missing)}"
    for code in codes:
        e = errors.error_for(code, "why", 400)
        assert type(e) is not errors.FieldhouseError and e.code == code


def test_an_unknown_code_is_a_generic_error():
    e = errors.error_for("brand_new", "later versions may add codes")
    assert type(e) is errors.FieldhouseError and e.code == "brand_new"
