"""Every test runs against the real server binary: ``fieldhouse serve`` started once per
session on a free loopback port (``$FIELDHOUSE_BIN``, default the repository's
``${CARGO_TARGET_DIR:-target}/debug/fieldhouse``), recording replays into a temporary
directory."""

from __future__ import annotations

import importlib.util
import os
import pathlib
import socket
import sys

import pytest

from fieldhouse import LocalServer

REPO = pathlib.Path(__file__).resolve().parents[3]


def default_binary() -> pathlib.Path:
    """Where cargo builds the server in this repository: ``CARGO_TARGET_DIR`` (relative
    to the workspace root, where scripts/python-tests runs cargo) or ``target``."""
    return REPO / (os.environ.get("CARGO_TARGET_DIR") or "target") / "debug" / "fieldhouse"


def load_example(name: str):
    """The module of ``clients/python/examples/{name}.py``, which its tests import (it may
    import the package, and the examples import nothing of each other)."""
    path = REPO / "clients" / "python" / "examples" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    # Registered before it runs: dataclasses look their module up by name.
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    binary = os.environ.get("FIELDHOUSE_BIN") or str(default_binary())
    replays = tmp_path_factory.mktemp("replays")
    with LocalServer(binary, args=["--replay-dir", str(replays)]) as s:
        yield s


@pytest.fixture
def client(server):
    return server.client()


@pytest.fixture
def closed_port_url():
    """A loopback address nothing listens on: a port the system handed out, closed again."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    return f"http://127.0.0.1:{port}"
