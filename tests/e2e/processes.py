"""Starting and stopping the real processes of the fleet for end-to-end tests."""

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

ROOT = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class Process:
    """A child process whose combined output goes to a log file, shown when a test fails."""

    def __init__(
        self,
        name: str,
        argv: list[str],
        env: dict[str, str],
        log_dir: Path,
        new_session: bool = False,
    ) -> None:
        self.name = name
        self.log_path = log_dir / f"{name}.log"
        self._log: IO[bytes] = self.log_path.open("wb")
        self.popen = subprocess.Popen(
            argv,
            cwd=ROOT,
            env=env,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            start_new_session=new_session,
        )

    def output(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def terminate(self, timeout: float = 20.0) -> int:
        """SIGTERM (to the whole group for `new_session` processes); SIGKILL after `timeout`."""
        if self.popen.poll() is None:
            try:
                os.killpg(self.popen.pid, signal.SIGTERM)
            except (ProcessLookupError, PermissionError):
                self.popen.send_signal(signal.SIGTERM)
        try:
            code = self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.popen.kill()
            code = self.popen.wait()
        self._log.close()
        return code


def python(*args: str) -> list[str]:
    return [sys.executable, *args]


def wait_until(
    condition: Callable[[], object],
    timeout: float,
    message: str,
    processes: list[Process] = (),
    interval: float = 0.5,
) -> object:  # type: ignore[assignment]
    """Poll `condition` until truthy; fail with the processes' output if a process died."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        for process in processes:
            if process.popen.poll() is not None:
                raise AssertionError(f"{process.name} exited early:\n{process.output()[-4000:]}")
        time.sleep(interval)
    logs = "\n".join(f"--- {p.name} ---\n{p.output()[-3000:]}" for p in processes)
    raise AssertionError(f"timed out after {timeout:.0f} s: {message}\n{logs}")
