"""A fieldhouse server of one's own: ``fieldhouse serve`` as a child process on a free
loopback port, for tests, examples and benchmarks that must not depend on a server
someone left running.

The binary is ``binary=``, else ``$FIELDHOUSE_BIN``, else ``fieldhouse`` on the PATH.
"""

from __future__ import annotations

import collections
import os
import re
import secrets
import shutil
import signal
import subprocess
import threading
import time

from .rest import Client

_LISTENING = re.compile(r"listening: open (http://\S+?)/")


def find_binary(binary: str | None = None) -> str:
    """The server binary to run, or a clear error saying how to name one."""
    path = binary or os.environ.get("FIELDHOUSE_BIN") or shutil.which("fieldhouse")
    if not path or not os.path.isfile(path):
        raise FileNotFoundError(
            f"no fieldhouse binary at {path!r}: build it (cargo build) and set FIELDHOUSE_BIN "
            "to target/debug/fieldhouse, or put fieldhouse on the PATH"
        )
    return path


class LocalServer:
    """``fieldhouse serve --no-demo`` on 127.0.0.1 and a port the system picks.

    Use it as a context manager; :attr:`url` and :attr:`admin_token` (a fresh random one
    unless given) are set once it listens, and :meth:`client` is a REST client with the
    token. ``args`` are more ``serve`` flags (``["--replay-dir", "replays"]``).
    """

    def __init__(
        self,
        binary: str | None = None,
        *,
        admin_token: str | None = None,
        args: tuple[str, ...] | list[str] = (),
        startup_timeout_s: float = 120.0,
    ):
        self.binary = find_binary(binary)
        self.admin_token = admin_token or secrets.token_hex(16)
        self.args = list(args)
        self.startup_timeout_s = startup_timeout_s
        self.url: str | None = None
        self.output: collections.deque[str] = collections.deque(maxlen=200)
        self._process: subprocess.Popen | None = None

    def __enter__(self) -> LocalServer:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def pid(self) -> int | None:
        """The server process's id while it runs (benchmarks read its CPU time)."""
        return self._process.pid if self._process is not None else None

    def client(self) -> Client:
        """A REST client for this server, with its admin token."""
        if self.url is None:
            raise RuntimeError("the server is not running")
        return Client(self.url, self.admin_token)

    def start(self) -> None:
        """Starts the server and waits for its ``listening`` line (the first start of a
        debug build reads or builds the basketball cost maps: seconds)."""
        env = dict(os.environ, FIELDHOUSE_ADMIN_TOKEN=self.admin_token)
        self._process = subprocess.Popen(
            [self.binary, "serve", "--no-demo", "--addr", "127.0.0.1:0", *self.args],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        found = threading.Event()

        def read() -> None:
            assert self._process is not None and self._process.stdout is not None
            for line in self._process.stdout:
                self.output.append(line.rstrip("\n"))
                m = _LISTENING.search(line)
                if m and self.url is None:
                    self.url = m.group(1)
                    found.set()

        # The reader keeps draining the log after the start, so the server never blocks
        # on a full pipe; the newest lines are kept for error messages.
        threading.Thread(target=read, name="fieldhouse-serve-log", daemon=True).start()
        deadline = time.monotonic() + self.startup_timeout_s
        while not found.wait(0.1):
            if self._process.poll() is not None or time.monotonic() > deadline:
                self.stop()
                log = "\n".join(self.output)
                raise RuntimeError(f"fieldhouse serve did not start listening:\n{log}")

    def stop(self) -> None:
        """Stops the server as an operator would (SIGTERM: matches end, sockets close)."""
        process, self._process = self._process, None
        if process is None or process.poll() is not None:
            return
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
