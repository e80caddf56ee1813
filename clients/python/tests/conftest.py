"""Starts the real graspd binary on ephemeral loopback ports for the client tests.

The binary comes from GRASPD_BIN, else <repo>/target/debug/graspd (``make test`` builds it).
"""

import os
import subprocess
import threading
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


class Server:
    def __init__(self, *args: str):
        binary = os.environ.get("GRASPD_BIN", str(REPO / "target" / "debug" / "graspd"))
        if not Path(binary).is_file():
            pytest.fail(f"{binary} not found: run `cargo build --bins` first (or set GRASPD_BIN)")
        env = {k: v for k, v in os.environ.items() if not k.startswith("GRASPD_")}
        env["GRASPD_LOG"] = "warn"
        self.process = subprocess.Popen(
            [binary, "--grpc-addr", "127.0.0.1:0", "--rest-addr", "127.0.0.1:0", *args],
            stdout=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            env=env,
            text=True,
        )
        line = self._listening_line(timeout=30)
        fields = dict(w.split("=", 1) for w in line.split() if "=" in w)
        self.grpc = fields["grpc"]
        self.rest = fields["rest"]

    def _listening_line(self, timeout: float) -> str:
        found = []

        def read():
            for line in self.process.stdout:
                if line.startswith("graspd listening "):
                    found.append(line)
                    return

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        reader.join(timeout)
        if not found:
            self.stop()
            pytest.fail("graspd did not print its listening line")
        return found[0]

    def stop(self):
        self.process.kill()
        self.process.wait()


@pytest.fixture(scope="session")
def server():
    s = Server("--max-tactile-sessions", "4")
    yield s
    s.stop()
