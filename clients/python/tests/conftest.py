"""Every test runs against the real server binary: ``fieldhouse serve`` started once per
session on a free loopback port (``$FIELDHOUSE_BIN``, default the repository's
target/debug/fieldhouse), recording replays into a temporary directory."""

from __future__ import annotations

import os
import pathlib

import pytest

from fieldhouse import LocalServer

REPO = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    binary = os.environ.get("FIELDHOUSE_BIN", str(REPO / "target" / "debug" / "fieldhouse"))
    replays = tmp_path_factory.mktemp("replays")
    with LocalServer(binary, args=["--replay-dir", str(replays)]) as s:
        yield s


@pytest.fixture
def client(server):
    return server.client()
