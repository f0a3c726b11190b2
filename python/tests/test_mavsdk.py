"""MAVSDK (version 4, the native binding from PyPI; an implementation nobody here wrote) as a
ground station against `isotrack sitl` (issue 33): it discovers the vehicle, its telemetry
matches isotrack's own trace of the same run, its health says ready to arm and its landed
state on the ground, then in the air once its Action plugin arms it, and its Offboard
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
from mavsdk.plugins.telemetry import FlightMode, LandedState, Telemetry  # noqa: E402

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
            # SYS_STATUS's pre-arm check and sensors: ready to arm; EXTENDED_SYS_STATE: a
            # disarmed fixed wing on the ground, then in the air once armed.
            assert until(lambda: tel.health().is_armable and tel.health().is_global_position_ok)
            assert until(lambda: tel.landed_state() == LandedState.ON_GROUND)
            act.arm()
            assert until(tel.armed)
            assert until(lambda: tel.landed_state() == LandedState.IN_AIR and tel.in_air())
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


def f32(x):
    import struct
    return struct.unpack("f", struct.pack("f", x))[0]


def test_mavsdk_autopilot_receives_the_laws_setpoints_from_fly():
    """MAVSDK's server side as a simple autopilot (armed, OFFBOARD: the pilot's doing, so `fly`
    runs without --take-control) sends `NAMED_VALUE_FLOAT` ISO_S; the `SET_ATTITUDE_TARGET`s
    that come back, stamped with each measurement's time, carry the Fig. 3 law's command for
    it, computed here independently: ki = 0, so omega = sat(kp (eps' + c1 tanh(eps / c2)))
    with eps = s - 10, eps' the backward difference (0 at the first sample), kp = 8, c1 = 0.05,
    c2 = 0.5, |omega| <= g tan(40 deg) / V; then roll = -atan(omega V / g), V = 30 m/s,
    g = 9.8 m/s^2, as the quaternion [cos(roll/2), sin(roll/2), 0, 0] (no altitude error:
    pitch 0), with the trim thrust (no airspeed reported)."""
    import json

    from mavsdk.plugins import action_server, mavlink_direct_server

    port = free_port()
    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.AUTOPILOT))
    sdk.add_any_connection(f"udpin://127.0.0.1:{port}")
    server = sdk.server_component()
    direct = mavlink_direct_server.MavlinkDirectServer(server)
    action = action_server.ActionServer(server)
    got = []
    direct.subscribe_message("SET_ATTITUDE_TARGET",
                             lambda m, _: got.append(json.loads(m.fields_json)))
    action.set_armed_state(True)
    action.set_flight_mode(action_server.FlightMode.OFFBOARD)
    # Near the level, so that no command saturates (each tests the formula, not the limit).
    values = [10.3, 10.25, 10.22, 10.2, 10.19, 10.185]
    p = subprocess.Popen(
        [cli(), "fly", str(ROOT / "scenarios" / "paper-fig3-uav.toml"),
         "--mavlink", f"udpout:127.0.0.1:{port}", "--max-duration-s", "5", "--timeout-s", "30"],
        stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        # fly's own setpoints stream (stamped 2^32 - 1, answering nothing) once it has found
        # the autopilot; then one measurement per answer.
        assert until(lambda: got), "fly never sent a setpoint"
        for k, v in enumerate(values):
            direct.send_message(mavlink_direct_server.MavlinkMessage(
                message_name="NAMED_VALUE_FLOAT", system_id=1, component_id=1,
                target_system_id=0, target_component_id=0,
                fields_json=json.dumps({"time_boot_ms": 1000 * k, "value": v, "name": "ISO_S"})))
            if k < 5:
                assert until(lambda: any(g["time_boot_ms"] == 1000 * k for g in got)), k
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    # max_duration is a failsafe: 75 once MAVSDK's server confirmed HOLD, 69 if it did not
    # (README's exit codes).
    assert p.returncode == 75 or (p.returncode == 69 and "did not confirm" in err), err
    assert "end         max_duration (5 measurements, 5 law commands)" in out
    answers = {}
    for g in got:
        answers.setdefault(g["time_boot_ms"], g)
    w_max = 9.8 * math.tan(math.radians(40.0)) / 30.0
    prev = None
    for k in range(5):
        s = f32(values[k])
        eps = s - 10.0
        eps_dot = 0.0 if prev is None else (eps - prev) / 1.0
        prev = eps
        w = max(-w_max, min(w_max, 8.0 * (eps_dot + 0.05 * math.tanh(eps / 0.5))))
        roll = -math.atan(w * 30.0 / 9.8)
        q = answers[1000 * k]["q"]
        assert abs(q[0] - math.cos(roll / 2)) < 1e-6 and abs(q[1] - math.sin(roll / 2)) < 1e-6, (k, q, roll)
        # No altitude from this autopilot: no altitude error, pitch 0.
        assert q[2] == 0 and q[3] == 0
        # Attitude and thrust (body rates ignored); no airspeed from it: the trim thrust 0.5.
        assert answers[1000 * k]["type_mask"] == 1 | 2 | 4
        assert answers[1000 * k]["thrust"] == 0.5
    # The measurement at t = 5 s is past --max-duration-s: no law answer for it.
    assert 5000 not in answers
