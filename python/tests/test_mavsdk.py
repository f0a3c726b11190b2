"""MAVSDK (version 4, the native binding from PyPI; an implementation nobody here wrote) as a
ground station against `isotrack sitl` (issue 33): it discovers the vehicle, its telemetry
matches isotrack's own trace of the same run, its Action plugin arms it, and its Offboard
plugin's attitude setpoint turns it as commanded. Real time at 5x: the waits are generous and
nothing asserts how long anything took."""

import csv
import math
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

mavsdk = pytest.importorskip("mavsdk")
from mavsdk import Configuration, ComponentType, Mavsdk  # noqa: E402
from mavsdk.plugins import offboard  # noqa: E402
from mavsdk.plugins.action import Action  # noqa: E402
from mavsdk.plugins.telemetry import FlightMode, Telemetry  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
R = 6_371_008.8  # mean Earth radius, m (docs/FLYING.md)
HOME = (47.397742, 8.545594, 488.0)  # the sitl.* defaults


def cli() -> str:
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not Path(exe).exists():
        pytest.skip(f"no isotrack binary at {exe} (build with cargo build --release)")
    return exe


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def until(what, timeout=30.0):
    t0 = time.time()
    while time.time() - t0 < timeout:
        v = what()
        if v:
            return v
        time.sleep(0.05)
    return None


def test_mavsdk_ground_station_watches_arms_and_turns_the_vehicle():
    port = free_port()
    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    sdk.add_any_connection(f"udpin://127.0.0.1:{port}")
    with tempfile.TemporaryDirectory() as d:
        p = subprocess.Popen(
            [cli(), "sitl", str(ROOT / "scenarios" / "paper-fig3-uav.toml"),
             "--set", "sim.duration_s=120", "--set", "initial.y_m=0", "--mavlink", f"udpout:127.0.0.1:{port}",
             "--speedup", "5", "--out", d],
            stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            systems = until(sdk.get_systems)
            assert systems, "MAVSDK found no system"
            system = systems[0]
            tel, act, off = Telemetry(system), Action(system), offboard.Offboard(system)
            pos = until(lambda: (lambda q: q if math.isfinite(q.latitude_deg) and q.latitude_deg != 0 else None)(tel.position()))
            assert pos is not None
            assert tel.armed() is False
            act.arm()
            assert until(tel.armed)
            # Roll -20 deg (left wing down): a coordinated left turn at
            # g tan(20 deg) / 30 m/s = 0.11902 rad/s through the autopilot's course loop.
            off.set_attitude(offboard.Attitude(-20.0, 0.0, 0.0, 0.5))
            off.start()
            assert until(lambda: tel.flight_mode() == FlightMode.OFFBOARD)
            euler = until(lambda: (lambda e: e if e.roll_deg < -15 else None)(tel.attitude_euler()))
            assert euler is not None, "never banked left"
            p.wait(timeout=120)
        finally:
            if p.poll() is None:
                p.kill()
        out, err = p.communicate()
        assert p.returncode == 0, err
        with open(Path(d, "trace.csv")) as f:
            rows = list(csv.DictReader(f))
    assert "run ended (completed)" in err
    # The telemetry position is one of the trace's rows (to the 1e-7 deg of
    # GLOBAL_POSITION_INT): the equirectangular map about home, inverted here independently.
    x = R * math.cos(math.radians(HOME[0])) * math.radians(pos.longitude_deg - HOME[1])
    y = R * math.radians(pos.latitude_deg - HOME[0])
    nearest = min(math.hypot(float(r["x_m"]) - x, float(r["y_m"]) - y) for r in rows)
    assert nearest < 0.05, nearest
    assert abs(pos.relative_altitude_m - 100.0) < 1.0
    assert abs(pos.absolute_altitude_m - (HOME[2] + 100.0)) < 1.0
    # Offboard: the commanded turn rate, then held by the autopilot at about -20 deg of roll.
    want = 9.8 * math.tan(math.radians(20.0)) / 30.0
    last = rows[-1]
    assert abs(float(last["omega_radps"]) - want) < 1e-5, last["omega_radps"]
    assert abs(math.degrees(float(last["roll_rad"])) + 20.0) < 2.0, last["roll_rad"]
    assert "armed by system 245" in err and "mode OFFBOARD by system 245" in err
