"""`isotrack sitl` against pymavlink, a MAVLink implementation nobody here wrote (issue 33):
pymavlink decodes every frame the simulated vehicle sends (checksums, ids, counts per simulated
second), drives it in lockstep as a companion would, and hostile traffic (bad checksums,
truncated frames, a flood, another system, setpoints for another system, NaN setpoints) neither
crashes it nor moves it: the Dubins robot commanded a zero turn rate ends exactly where a
straight line at 0.5 m/s puts it."""

import csv
import json
import os
import random
import re
import socket
import subprocess
import tempfile
import time
from pathlib import Path

import pytest

os.environ.setdefault("MAVLINK20", "1")
mavutil = pytest.importorskip("pymavlink.mavutil")

ROOT = Path(__file__).resolve().parents[2]
COMPANION = (1, 191)


def cli() -> str:
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not Path(exe).exists():
        pytest.skip(f"no isotrack binary at {exe} (build with cargo build --release)")
    return exe


def start_sitl(out, *extra):
    """A lockstep vehicle on a port of its own (port 0: the vehicle says which on stderr)."""
    p = subprocess.Popen(
        [cli(), "sitl", "--mavlink", "udpin:127.0.0.1:0", "--lockstep", "--out", out,
         "--set", "sim.duration_s=20", *extra],
        stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    line = p.stderr.readline()
    m = re.search(r"vehicle on 127\.0\.0\.1:(\d+)", line)
    assert m, line
    return p, int(m.group(1))


def companion(port):
    c = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}",
                                   source_system=COMPANION[0], source_component=COMPANION[1])
    c.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
                         mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    return c


def take_control(c, seen):
    """Arm and OFFBOARD (PX4 custom main mode 6); returns the ACK results. Every message
    received meanwhile goes into `seen`, and an ISO_S is answered as `drive` does. As PX4
    wants, a setpoint (stamped 2^32 - 1: it answers no sample) streams before the switch;
    each COMMAND_ACK is addressed to the companion (MAVLink 2's target extension fields)."""
    acks = []
    for cmd, p in [(400, [1, 0, 0]), (176, [1, 6, 0])]:
        if cmd == 176:
            yaw_rate_setpoint(c, 2**32 - 1, 0.0)
        c.mav.command_long_send(1, 1, cmd, 0, *p, 0, 0, 0, 0)
        while True:
            m = c.recv_match(blocking=True, timeout=30)
            assert m is not None, "no COMMAND_ACK"
            seen.append(m)
            if m.get_type() == "COMMAND_ACK" and m.command == cmd:
                assert (m.target_system, m.target_component) == COMPANION, m
                acks.append(m.result)
                break
    return acks


def yaw_rate_setpoint(c, ms, rate, system=1, src=None):
    # type_mask: ignore roll rate, pitch rate, throttle and attitude: a yaw-rate setpoint.
    c.mav.set_attitude_target_send(ms, system, 1, 1 | 2 | 64 | 128, [1, 0, 0, 0], 0, 0, rate, 0)


def drive(c, got, hostile=None):
    """Answers every ISO_S with a zero yaw rate until the vehicle powers off; returns every
    message received (pymavlink's BAD_DATA included), after those already in `got`."""
    for m in list(got):
        if m.get_type() == "NAMED_VALUE_FLOAT" and m.name == "ISO_S":
            yaw_rate_setpoint(c, m.time_boot_ms, 0.0)
    while True:
        m = c.recv_match(blocking=True, timeout=60)
        assert m is not None, "the vehicle went quiet"
        got.append(m)
        t = m.get_type()
        if t == "NAMED_VALUE_FLOAT" and m.name == "ISO_S":
            if hostile:
                hostile(m.time_boot_ms)
            yaw_rate_setpoint(c, m.time_boot_ms, 0.0)
        if t == "HEARTBEAT" and m.system_status == mavutil.mavlink.MAV_STATE_POWEROFF:
            return got


def test_pymavlink_decodes_every_message_sitl_sends():
    with tempfile.TemporaryDirectory() as d:
        p, port = start_sitl(d)
        c = companion(port)
        got = []
        assert take_control(c, got) == [0, 0]  # MAV_RESULT_ACCEPTED
        got = drive(c, got)
        p.wait(timeout=120)
        assert p.returncode == 0, p.stderr.read()
    types = [m.get_type() for m in got]
    assert "BAD_DATA" not in types
    assert all(m.get_srcSystem() == 1 and m.get_srcComponent() == 1 for m in got)
    want = {"HEARTBEAT": 0, "SYS_STATUS": 1, "GLOBAL_POSITION_INT": 33, "LOCAL_POSITION_NED": 32,
            "ATTITUDE": 30, "VFR_HUD": 74, "HOME_POSITION": 242, "SYSTEM_TIME": 2,
            "NAMED_VALUE_FLOAT": 251, "COMMAND_ACK": 77, "EXTENDED_SYS_STATE": 245}
    for name, msg_id in want.items():
        ms = [m for m in got if m.get_type() == name]
        assert ms, f"no {name}"
        assert all(m.get_msgId() == msg_id for m in ms)
    count = {t: types.count(t) for t in set(types)}
    # 20 s at 100 Hz: samples at t = 0, 0.01, ..., 20 (2001); telemetry at the recording
    # rate, 10 Hz (201 rows); the once-a-second group at t = 0, 1, ..., 20 (21).
    assert count["NAMED_VALUE_FLOAT"] == 2001
    for t in ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "ATTITUDE", "VFR_HUD"):
        assert count[t] == 201, (t, count[t])
    for t in ("SYS_STATUS", "SYSTEM_TIME", "HOME_POSITION"):
        assert count[t] == 21, (t, count[t])
    # EXTENDED_SYS_STATE with the group and after each ACK; a ground vehicle on the ground.
    assert count["EXTENDED_SYS_STATE"] >= 21 + 2
    assert all(m.landed_state == mavutil.mavlink.MAV_LANDED_STATE_ON_GROUND
               for m in got if m.get_type() == "EXTENDED_SYS_STATE")
    # Heartbeats: the 21 of the group, one after each ACK, the first of the three at the end
    # (and one a wall-clock second while the vehicle waits, if it ever waits that long).
    assert count["HEARTBEAT"] >= 21 + 2 + 1
    times = [m.time_boot_ms for m in got if m.get_type() == "NAMED_VALUE_FLOAT"]
    assert times == [10 * k for k in range(2001)]
    # Home: PX4's SITL default, as the scenario keys' defaults say.
    h = next(m for m in got if m.get_type() == "HOME_POSITION")
    assert (h.latitude, h.longitude, h.altitude) == (473977420, 85455940, 488000)


def test_hostile_traffic_neither_crashes_nor_moves_the_vehicle():
    random.seed(33)
    with tempfile.TemporaryDirectory() as d:
        p, port = start_sitl(d)
        c = companion(port)
        got = []
        assert take_control(c, got) == [0, 0]
        raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        stranger = mavutil.mavlink.MAVLink(None, srcSystem=77, srcComponent=1)
        mine = mavutil.mavlink.MAVLink(None, srcSystem=COMPANION[0], srcComponent=COMPANION[1])
        def frame(mav, ms, q=(0.6, 0.8, 0, 0), rate=1.0, system=1):
            return mav.set_attitude_target_encode(ms, system, 1, 1 | 2 | 64, list(q), 0, 0,
                                                  rate, 0).pack(mav)
        def hostile(ms):
            if ms % 500:
                return
            good = frame(mine, ms, rate=2.0)
            bad_crc = good[:-2] + bytes([good[-2] ^ 0xFF, good[-1]])
            nan = float("nan")
            for b in [
                bad_crc,                                  # wrong checksum
                good[: len(good) // 2],                   # truncated
                bytes(random.getrandbits(8) for _ in range(300)),  # noise
                frame(stranger, ms, rate=2.0),            # another system's setpoint
                frame(mine, ms, rate=2.0, system=2),      # a setpoint for another system
                frame(mine, ms, q=(nan, 0, 0, 0), rate=nan),  # NaN setpoint
                frame(mine, ms, q=(0, 0, 0, 0), rate=float("inf")),
            ]:
                raw.sendto(b, ("127.0.0.1", port))
            for _ in range(200):                          # a flood
                raw.sendto(bytes(random.getrandbits(8) for _ in range(64)), ("127.0.0.1", port))
        got = drive(c, got, hostile)
        p.wait(timeout=120)
        assert p.returncode == 0, p.stderr.read()
        with open(Path(d, "trace.csv")) as f:
            rows = list(csv.DictReader(f))
        summary = json.loads(Path(d, "summary.json").read_text())
    assert summary["outcome"] == "completed"
    # Start (10, 0) heading south (-pi/2), 0.5 m/s, turn rate 0 throughout: (10, -10) at 20 s.
    last = rows[-1]
    assert float(last["t_s"]) == 20.0
    assert abs(float(last["x_m"]) - 10.0) < 1e-9
    assert abs(float(last["y_m"]) + 10.0) < 1e-9
    assert all(float(r["omega_radps"]) == 0.0 for r in rows)
    assert not [m for m in got if m.get_type() == "BAD_DATA"]


def test_a_pymavlink_ground_station_hands_over_to_fly():
    """docs/FLYING.md's ground-station workflow: `fly` waits (no --take-control), pymavlink as
    the ground station (system 255) arms the vehicle and switches it to OFFBOARD, and fly's law
    then flies it: its setpoints are accepted (the lockstep vehicle advances on them) until
    --max-duration-s, a failsafe whose HOLD the vehicle confirms (exit 75)."""
    with tempfile.TemporaryDirectory() as d:
        p, port = start_sitl(d, "--timeout-s", "5")
        fly = subprocess.Popen(
            [cli(), "fly", "--mavlink", f"udpout:127.0.0.1:{port}", "--timeout-s", "20",
             "--max-duration-s", "2"],
            stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            g = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255,
                                           source_component=190)
            g.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS,
                                 mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            assert g.recv_match(type="HEARTBEAT", blocking=True, timeout=30) is not None
            acks = []
            for cmd, prm in [(400, [1, 0, 0]), (176, [1, 6, 0])]:
                # OFFBOARD is refused (1, TEMPORARILY_REJECTED, as PX4) until fly's setpoints
                # stream: the pilot tries again.
                for _ in range(50):
                    g.mav.command_long_send(1, 1, cmd, 0, *prm, 0, 0, 0, 0)
                    while True:
                        m = g.recv_match(type="COMMAND_ACK", blocking=True, timeout=30)
                        assert m is not None, "no COMMAND_ACK"
                        if m.command == cmd:
                            break
                    if m.result != 1:
                        break
                    time.sleep(0.2)
                acks.append(m.result)
            assert acks == [0, 0]
            out, err = fly.communicate(timeout=120)
        finally:
            for q in (fly, p):
                if q.poll() is None:
                    q.kill()
        assert fly.returncode == 75, err
        # A planned end, not called a failsafe (issue 33).
        assert "ended at its --max-duration-s" in err and "ended by a failsafe" not in err, err
        m = re.search(r"end         max_duration \((\d+) measurements, (\d+) law commands\)", out)
        assert m and int(m.group(2)) > 0, out + err
        p.wait(timeout=60)
