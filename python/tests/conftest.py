"""Fixtures: the real ``armgate-sim`` on a free loopback port, and a scripted fake controller.

The simulator binary is ``$ARMGATE_SIM`` if set, else ``target/debug/armgate-sim`` of this
repository (built with cargo if missing).
"""

from __future__ import annotations

import importlib
import os
import re
import socket
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, Iterator, List, Optional

import pytest

import armgate

REPO = Path(__file__).resolve().parents[2]


def built_binary(package: str, variable: str) -> Path:
    """``$variable`` if set, else ``target/debug/<package>`` of this repository (built with
    cargo if missing)."""
    given = os.environ.get(variable)
    if given:
        return Path(given)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    binary = target / "debug" / package
    if not binary.exists():
        subprocess.run(["cargo", "build", "-q", "-p", package], cwd=REPO, check=True)
    return binary


def sim_binary() -> Path:
    return built_binary("armgate-sim", "ARMGATE_SIM")


def viz_binary() -> Path:
    """The tool behind ``armgate urdf`` and ``armgate record``."""
    return built_binary("armgate-viz", "ARMGATE_VIZ")


def require_viz_package(name: str):
    """Imports a PyPI package the URDF and MCAP tests read with: skipped without it, unless
    ``ARMGATE_REQUIRE_VIZ=1`` (CI sets it): then the test fails."""
    try:
        return importlib.import_module(name)
    except ImportError:
        if os.environ.get("ARMGATE_REQUIRE_VIZ") == "1":
            pytest.fail(f"{name} is not installed (pip install {name})")
        pytest.skip(f"{name} is not installed")


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Sim:
    """A running ``armgate-sim``."""

    def __init__(
        self, robot: str, extra: List[str], ready: bool = True, port: Optional[int] = None
    ) -> None:
        self.robot = REPO / "robots" / f"{robot}.toml"
        self.port = port or free_port()
        if "--key" in extra and "--state" not in extra:
            # A test's replay state is its own, never the user's default location.
            self._state = Path(tempfile.mkdtemp(prefix="armgate-state-"))
            extra = [*extra, "--state", str(self._state / "replay")]
        self.process = subprocess.Popen(
            [str(sim_binary()), "--quiet", "--robot", str(self.robot),
             "--listen", f"127.0.0.1:{self.port}", *extra],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        if ready:
            self.wait_ready()
        else:
            self.wait_listening()

    def wait_listening(self) -> None:
        """Until the simulator's port is bound, sending it nothing it would serve (a restart
        test must not spend the controller's replay reservation): one byte, which a bound port
        drops or refuses in a text and an unbound one answers with ICMP port unreachable."""
        deadline = time.monotonic() + 20
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.connect(("127.0.0.1", self.port))
            probe.settimeout(0.05)
            while time.monotonic() < deadline:
                if self.process.poll() is not None:
                    raise RuntimeError(f"armgate-sim exited: {self.process.stderr.read()!r}")
                try:
                    probe.send(b"\0")
                    probe.recv(64)
                    return
                except socket.timeout:
                    return
                except ConnectionRefusedError:
                    time.sleep(0.02)
        raise RuntimeError("armgate-sim did not listen within 20 s")

    def wait_ready(self) -> None:
        deadline = time.monotonic() + 20
        # A simulator with --key answers only signed requests.
        args = self.process.args
        key = args[args.index("--key") + 1] if "--key" in args else None
        with armgate.Arm(
            "127.0.0.1", self.port, timeout=0.1, retries=0, joints=1, key=key, link_id=200
        ) as probe:
            while time.monotonic() < deadline:
                if self.process.poll() is not None:
                    raise RuntimeError(f"armgate-sim exited: {self.process.stderr.read()!r}")
                try:
                    probe.get_tcp_pose()
                    break
                except armgate.ArmError:
                    time.sleep(0.05)
            else:
                raise RuntimeError("armgate-sim did not answer within 20 s")
            # The drives start at once; motion is refused until they run.
            while time.monotonic() < deadline:
                try:
                    if probe.get_status().drive_state == armgate.DriveState.RUNNING:
                        return
                    time.sleep(0.05)
                except armgate.ControllerTooOld:
                    # No status request: the start takes 12 cycles (0.23 s at 51 Hz).
                    time.sleep(1.0)
                    return
                except armgate.ArmError:
                    time.sleep(0.05)
        raise RuntimeError("the simulated drives did not start within 20 s")

    def home(self) -> dict:
        """The home joints and tool pose, as ``armgate-sim --print-home`` prints them."""
        out = subprocess.run(
            [str(sim_binary()), "--robot", str(self.robot), "--print-home"],
            capture_output=True, text=True, check=True,
        ).stdout
        numbers = lambda line: [float(v) for v in re.findall(r"-?\d+\.\d+", line.split(":", 1)[1])]  # noqa: E731
        # "home joints (rad; m for prismatic joints): ..." -> key "home joints".
        lines = {line.split(":")[0].split("(")[0].strip(): line for line in out.splitlines()}
        return {
            "joints": numbers(lines["home joints"]),
            "xyz": numbers(lines["tool position"]),
            "quaternion": numbers(lines["tool quaternion"]),
            "rpy": numbers(lines["tool RPY"]),
        }

    def stop(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


@pytest.fixture
def sim_factory() -> Iterator[Callable[..., Sim]]:
    started: List[Sim] = []

    def start(
        robot: str = "ranger-mk1", *extra: str, ready: bool = True, port: Optional[int] = None
    ) -> Sim:
        sim = Sim(robot, list(extra), ready=ready, port=port)
        started.append(sim)
        return sim

    yield start
    for sim in started:
        sim.stop()


@pytest.fixture
def mk1(sim_factory: Callable[..., Sim]) -> Sim:
    return sim_factory("ranger-mk1")


@pytest.fixture
def mk2(sim_factory: Callable[..., Sim]) -> Sim:
    return sim_factory("ranger-mk2")


class FakeController:
    """A UDP server on a free loopback port that answers each datagram with what ``script``
    returns for it (a list of datagrams), and records what it received."""

    def __init__(self, script: Callable[[bytes], List[bytes]]) -> None:
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.bind(("127.0.0.1", 0))
        self.socket.settimeout(0.05)
        self.port = self.socket.getsockname()[1]
        self.received: List[bytes] = []
        self._script = script
        self._running = True
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while self._running:
            try:
                datagram, peer = self.socket.recvfrom(64)
            except socket.timeout:
                continue
            self.received.append(datagram)
            for answer in self._script(datagram):
                self.socket.sendto(answer, peer)

    def close(self) -> None:
        self._running = False
        self._thread.join()
        self.socket.close()


@pytest.fixture
def fake_factory() -> Iterator[Callable[[Callable[[bytes], List[bytes]]], FakeController]]:
    fakes: List[FakeController] = []

    def start(script: Callable[[bytes], List[bytes]]) -> FakeController:
        fake = FakeController(script)
        fakes.append(fake)
        return fake

    yield start
    for fake in fakes:
        fake.close()


def text(s: str) -> bytes:
    """An ER/WN text datagram."""
    return s.encode("ascii").ljust(31, b"\0")


def reply(chars: str, values: Optional[List[float]] = None, index: int = 0) -> bytes:
    """A normal reply datagram."""
    return armgate.wire.encode(chars, values or [], index)
