"""The REST client against the real server: matches, replays, and each refusal as its
exception class."""

from __future__ import annotations

import time

import pytest

from fieldhouse import Client
from fieldhouse.errors import BadId, BadQuery, BadScenario, FieldhouseError, Forbidden, NotFound

ONE_BALL = {
    "sport": "baseball",
    "mode": "fast",
    "agents": [{"id": "cf", "strategy": "chapman"}],
    "options": {
        "launches": [{"time_s": 0.0, "speed_m_s": 34.0, "elevation_deg": 45.0, "azimuth_deg": 45.0}]
    },
}


def wait_ended(client: Client, match_id: str) -> dict:
    deadline = time.monotonic() + 30
    while (m := client.get_match(match_id))["status"] != "ended":
        assert time.monotonic() < deadline, m
        time.sleep(0.05)
    return m


def test_create_list_get_delete(client):
    created = client.create_match(
        {
            "sport": "basketball",
            "name": "rest test",
            "agents": [
                {"id": "o1", "team": "offense", "bot": True},
                {"id": "d1", "team": "defense", "strategy": "defense"},
            ],
        }
    )
    assert set(created.bot_tokens) == {"o1"} and len(created.bot_tokens["o1"]) == 32
    listed = {m["id"]: m for m in client.list_matches()}
    assert listed[created.id]["name"] == "rest test"
    assert [a["bot_slot"] for a in listed[created.id]["agents"]] == [True, False]
    full = client.get_match(created.id)
    assert (
        full["scenario"]["sport"] == "basketball" and full["match"]["perception_every_ticks"] == 15
    )
    client.delete_match(created.id)
    with pytest.raises(NotFound) as e:
        client.get_match(created.id)
    assert e.value.status == 404 and created.id in e.value.message


def test_a_bad_scenario_names_the_field(client):
    with pytest.raises(BadScenario) as e:
        client.create_match({"sport": "baseball", "agents": [{"id": "cf", "strategy": "lott"}]})
    assert e.value.status == 422
    assert e.value.message.startswith("agents[0].strategy: ") and "lott" in e.value.message


def test_admin_token_is_checked(server):
    with pytest.raises(Forbidden):
        Client(server.url, "not-the-token-at-all").create_match({"sport": "baseball"})
    anonymous = Client(server.url)
    anonymous.admin_token = None  # whatever FIELDHOUSE_ADMIN_TOKEN the runner has
    with pytest.raises(FieldhouseError, match="needs the admin token"):
        anonymous.create_match({"sport": "baseball"})


def test_replays_are_listed_and_downloaded(client, tmp_path):
    created = client.create_match(ONE_BALL)
    ended = wait_ended(client, created.id)
    assert ended["score"]["balls"] == 1
    replay_id = ended["replay"]
    deadline = time.monotonic() + 30
    while not any(r["id"] == replay_id and r.get("complete") for r in client.list_replays()):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    size = client.download_replay(replay_id, tmp_path / "r.jsonl.zst")
    data = client.download_replay(replay_id)
    assert data[:4] == b"\x28\xb5\x2f\xfd"  # a zstd frame: format 2
    assert (tmp_path / "r.jsonl.zst").read_bytes() == data and size == len(data)
    with pytest.raises(BadId):
        client.download_replay("../etc")
    with pytest.raises(NotFound):
        client.download_replay("no-such-replay")


def test_replays_are_listed_a_page_at_a_time_newest_first(client):
    ours = []
    for _ in range(3):
        ours.append(wait_ended(client, client.create_match(ONE_BALL).id)["replay"])
    deadline = time.monotonic() + 30
    while not all(
        any(r["id"] == id and r.get("complete") for r in client.list_replays()) for id in ours
    ):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    # A page of one at a time finds what one big page does, in the same order: the
    # newest first, so ours (finished one after another) come last-finished first.
    paged = [r["id"] for r in client.list_replays(page_size=1) if r["id"] in ours]
    whole = [r["id"] for r in client.list_replays(page_size=1000) if r["id"] in ours]
    assert paged == whole == ours[::-1]
    assert len(client.list_replays(limit=2)) == 2
    with pytest.raises(BadQuery):
        client._json("GET", "/api/replays?limit=0")


def test_without_a_server_the_error_says_how_to_start_one(closed_port_url):
    for call in (
        lambda c: c.list_matches(),
        lambda c: c.create_match(ONE_BALL),
        lambda c: c.delete_match("m"),
    ):
        with pytest.raises(FieldhouseError) as e:
            call(Client(closed_port_url, "t" * 16))
        assert e.value.code == "unreachable"
        message = str(e.value)
        assert closed_port_url in message
        assert "fieldhouse serve" in message and "cargo run --release -- serve" in message


def test_the_url_comes_from_the_argument_then_fieldhouse_url_then_the_default(monkeypatch):
    monkeypatch.delenv("FIELDHOUSE_URL", raising=False)
    assert Client().url == "http://127.0.0.1:7878"
    monkeypatch.setenv("FIELDHOUSE_URL", "http://fieldhouse.example:9000/")
    assert Client().url == "http://fieldhouse.example:9000"
    assert Client("http://127.0.0.1:1").url == "http://127.0.0.1:1"


def test_a_match_created_with_record_false_keeps_no_replay(client):
    kept = client.create_match(ONE_BALL)
    unrecorded = client.create_match(ONE_BALL, record=False)
    try:
        assert wait_ended(client, kept.id)["replay"] is not None
        assert wait_ended(client, unrecorded.id)["replay"] is None
        matches = {r["match"] for r in client.list_replays()}
        assert kept.id in matches and unrecorded.id not in matches
    finally:
        client.delete_match(kept.id)
        client.delete_match(unrecorded.id)
