"""Identification from a robot's log (issue 47): ``identify_log`` and ``identify DESCRIPTION --data FILE``.

The log: the Panda arm of example-robot-data (tests/corpus.py ``NAMED["panda"]``, fingers welded, 7 joints)
with planted parameters (``panda_link3``: mass x 1.2, centre of mass moved by (10, -5, 8) mm;
``panda_joint2`` damping 0.5; ``panda_joint4`` armature 0.05), written as MJCF at full precision
(``mjcf_from_model``: the same frames and H as the library's tree) and simulated by MuJoCo (semi-implicit
Euler at 1 ms, a computed-torque servo along a sum of five sines per joint, 10 s). The truth is the planted
model's parameter vector. Noise as the issue asks: positions 1e-4 rad, efforts 1% of each joint's range
(new noise per seed; the simulation runs once).

Measured: the 95% intervals cover the truth for 90.7% of (seed, base parameter) pairs (the issue's 90-99%),
with Savitzky-Golay of order 5 (window 169 samples, 10 Hz). Planted wrong once each (by hand): order 3 (its
acceleration ~1% low at 1 Hz) covered 82%; without the Newey-West correction 72-79%.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from lxml import etree

from cli_runner import run_cli
from corpus import panda_arm

pytestmark = pytest.mark.usefixtures("corpus_installed")

SEEDS = 50


def _arm_urdf(out):
    """The arm with link3's mass x 1.2 and its centre of mass moved, joint2's damping 0.5 (the planted truth)."""
    def plant(root):
        for j in root.findall("joint"):
            if j.get("name") == "panda_joint2":
                j.find("dynamics").set("damping", "0.5")
        for link in root.findall("link"):
            if link.get("name") == "panda_link3":
                i = link.find("inertial")
                i.find("mass").set("value", repr(float(i.find("mass").get("value")) * 1.2))
                o = i.find("origin")
                o.set("xyz", " ".join(repr(float(x)) for x in np.array(o.get("xyz").split(), float)
                                      + [0.010, -0.005, 0.008]))

    return panda_arm(out, edit=plant)


def _params(urdf):
    from urdf2links.identification import ParameterSet
    from urdf2links.parsers.parts import parts_model, robot_parts

    parts = robot_parts(urdf)
    joints = {j.name: j for j, _b in parts.joints}
    model = parts_model(parts).model
    return parts, model, ParameterSet.from_model(model, damping={c: joints[c].damping for c in model.coordinate_names})


def _simulate(urdf, armature, seconds=10.0, seed=47):
    """(names, t, q, qd, tau (S, 7)) of MuJoCo running the planted arm's MJCF twin under computed torque."""
    import mujoco
    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
    from urdf2links.parsers.robot_file import load_robot
    from urdf2links.robot_logs import angular_limits

    parts, model, _ = _params(urdf)
    damping = {j.name: j.damping for j, _b in parts.joints}
    root = etree.fromstring(mjcf_from_model(model, gravity=model.gravity_vector).xml.encode())
    root.find("option").remove(root.find("option").find("flag"))     # damping on
    for j in root.find("worldbody").iter("joint"):
        j.set("damping", repr(float(damping[j.get("name")])))
        if j.get("name") in armature:
            j.set("armature", repr(armature[j.get("name")]))
    m = mujoco.MjModel.from_xml_string(etree.tostring(root, encoding="unicode"))
    m.opt.timestep = 1e-3
    d = mujoco.MjData(m)
    names = tuple(model.coordinate_names)
    lim = angular_limits(load_robot(urdf))
    lo, hi = np.array([lim[c][0] for c in names]), np.array([lim[c][1] for c in names])
    mid, amp = 0.5 * (lo + hi), np.minimum(0.3 * (hi - lo), 1.0)
    f = np.array([0.1, 0.23, 0.37, 0.61, 0.9])
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, (7, f.size))
    a = rng.uniform(0.5, 1, (7, f.size)) / np.arange(1, f.size + 1) ** 0.5
    a /= a.sum(1, keepdims=True)
    w = 2 * np.pi * f

    def ref(t):
        s, c = np.sin(w * t + phase), np.cos(w * t + phase)
        return mid + amp * (a * s).sum(1), amp * (a * w * c).sum(1), -amp * (a * w ** 2 * s).sum(1)
    d.qpos[:], d.qvel[:], _ = ref(0.0)
    S = int(round(seconds / m.opt.timestep))
    out = np.empty((S, 22))
    M = np.empty((7, 7))
    for k in range(S):
        mujoco.mj_forward(m, d)
        mujoco.mj_fullM(m, d, M)
        qr, vr, ar = ref(d.time)
        tau = M @ (ar + 100.0 * (qr - d.qpos) + 20.0 * (vr - d.qvel)) + d.qfrc_bias + m.dof_damping * d.qvel
        d.qfrc_applied[:] = tau
        out[k] = np.concatenate([[d.time], d.qpos, d.qvel, tau])
        mujoco.mj_step(m, d)
    assert np.all(np.diff(out[:, 0]) > 0), "MuJoCo reset its data: the run went unstable"
    return names, out[:, 0], out[:, 1:8], out[:, 8:15], out[:, 15:22]


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    """The description (unplanted arm), the truth, the clean simulated log."""
    folder = tmp_path_factory.mktemp("logs")
    desc_urdf = panda_arm(folder / "panda_arm.urdf")
    planted = _arm_urdf(folder / "panda_planted.urdf")
    _, _, desc = _params(desc_urdf)
    _, _, truth = _params(planted)
    tv = truth.values.copy()
    tv[truth.index("armature_panda_joint4")] = 0.05
    names, t, q, qd, tau = _simulate(planted, {"panda_joint4": 0.05})
    return {"desc": desc, "truth": tv, "names": names, "t": t, "q": q, "qd": qd, "tau": tau, "urdf": desc_urdf,
            "folder": folder}


def _noisy(arm, seed):
    from urdf2links.robot_logs import RobotLog

    rng = np.random.default_rng(seed)
    q = arm["q"] + 1e-4 * rng.standard_normal(arm["q"].shape)
    tau = arm["tau"] + 0.01 * np.ptp(arm["tau"], axis=0) * rng.standard_normal(arm["tau"].shape)
    return RobotLog(times=np.round(arm["t"], 9), names=arm["names"], positions=q, velocities=arm["qd"],
                    efforts=tau, source=f"simulated seed {seed}")


def _fit(arm, log, base=None):
    from urdf2links.identification.from_log import identify_log
    from urdf2links.robot_logs import check_log, derivatives

    log = check_log(log, joints=arm["desc"].model.coordinate_names)
    return identify_log(arm["desc"], derivatives(log, order=5), base=base)


def test_intervals_cover_the_truth_over_50_seeds(arm):
    """50 noise seeds on one simulation (array path; the bag and CSV paths are proven equal below): the
    pooled coverage of the 95% intervals of every base parameter within 90-99% (module doc: measured 90.7%)."""
    first = _fit(arm, _noisy(arm, 0))
    base = first.base
    truth = base.beta(arm["truth"])
    covered = [first.acceleration.covers(truth)]
    for seed in range(1, SEEDS):
        covered.append(_fit(arm, _noisy(arm, seed), base=base).acceleration.covers(truth))
    rate = float(np.mean(covered))
    print(f"coverage of the 95% intervals over {SEEDS} seeds x {base.r} base parameters: {rate:.3f}")
    assert 0.90 <= rate <= 0.99, rate
    assert not first.acceleration.warnings          # condition number ~65: the intervals are stated, no warning


def test_bag_and_csv_give_the_array_fit(arm, tmp_path):
    """The log written as a ROS 2 bag (MCAP, rosbags' own writer) and as CSV, read back by read_log, gives the
    array path's base parameters and intervals (to 1e-9 relative: the bag's times pass through integer
    nanoseconds)."""
    from test_robot_logs import _write_bag
    from urdf2links.robot_logs import read_log, write_csv

    for seed in (0, 1):
        log = _noisy(arm, seed)
        ref = _fit(arm, log)
        _write_bag(tmp_path / f"bag{seed}", log)
        write_csv(log, tmp_path / f"log{seed}.csv")
        for src in (read_log(tmp_path / f"bag{seed}"), read_log(tmp_path / f"log{seed}.csv")):
            got = _fit(arm, src, base=ref.base)
            np.testing.assert_allclose(got.acceleration.beta, ref.acceleration.beta, rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(got.acceleration.std, ref.acceleration.std, rtol=1e-6)


def test_energy_form_agrees_with_the_accelerations(arm):
    """The energy form (no accelerations) on the same log gives the same base parameters within their combined
    standard deviations (measured: within 0.03), with wider intervals: it has fewer equations."""
    li = _fit(arm, _noisy(arm, 3))
    assert li.energy is not None
    assert np.max(np.abs(li.agreement)) < 2.0
    assert np.median(li.energy.std / li.acceleration.std) > 1.0


def _csv(arm, tmp_path, edit=None):
    from urdf2links.robot_logs import write_csv

    log = _noisy(arm, 5)
    p = write_csv(log, tmp_path / "log.csv")
    if edit:
        lines = p.read_text().splitlines()
        lines = edit(lines)
        p.write_text("\n".join(lines) + "\n")
    return p


def test_cli_fits_a_csv_log(arm, tmp_path):
    """``identify ARM --data log.csv``: exit 0, the JSON's base parameters and both forms."""
    p = _csv(arm, tmp_path)
    r = run_cli("identify", str(arm["urdf"]), "--data", str(p), "--out", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "out" / "identify.json").read_text())
    assert s["summary"]["base_parameters"] == len(s["table"]) > 40
    assert "energy" in s["table"][0] and (tmp_path / "out" / "filter.png").is_file()


@pytest.mark.parametrize("case", ["nan", "unknown"])
def test_cli_bad_data_is_a_named_one_line_error(arm, tmp_path, case):
    """Bad data reaches the command as its named error on one line: a NaN names the column and the row; a
    joint unknown to the description names it with a did-you-mean. Exit status 2, nothing fitted."""
    def nan(lines):
        cells = lines[11].split(",")
        cells[3] = "nan"
        lines[11] = ",".join(cells)
        return lines

    def unknown(lines):
        lines[0] = lines[0].replace("panda_joint3.", "panda_jiont3.")
        return lines
    p = _csv(arm, tmp_path, nan if case == "nan" else unknown)
    header = p.read_text().splitlines()[0].split(",")
    r = run_cli("identify", str(arm["urdf"]), "--data", str(p), "--out", str(tmp_path / "out"))
    assert r.returncode == 2
    from urdf2links.compilation import WHAT      # numba's one-time compile note, on a cold cache only

    msg = "\n".join(line for line in r.stderr.strip().splitlines() if WHAT not in line)
    assert "\n" not in msg and msg.startswith("urdf2links identify: ")
    if case == "nan":
        assert header[3] in msg and "row 11" in msg
    else:
        assert "panda_jiont3" in msg and "panda_joint3" in msg
    assert not (tmp_path / "out" / "identify.json").exists()

# -- a floating base in flight -------------------------------------------------------------------------------
def _flight(urdf, seconds=3.0, seed=7):
    """MuJoCo flies the arm with a floating root (the MJCF twin's six base joints, no force on them, gravity
    on): the joints driven by open-loop sums of sines (torques between the links). Returns times, base poses (positions, quaternions wxyz),
    joint positions."""
    import mujoco
    from scipy.spatial.transform import Rotation
    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
    from urdf2links.parsers.robot_file import load_robot

    model = load_robot(urdf, floating_base=True)
    m = mujoco.MjModel.from_xml_string(mjcf_from_model(model, gravity=model.gravity_vector).xml)
    m.opt.timestep = 1e-3
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    f, ph = np.array([0.4, 0.9, 1.3]), rng.uniform(0, 2 * np.pi, (7, 3))
    w = 2 * np.pi * f
    amp = np.array([0.05, 0.3, 0.15, 0.15, 0.03, 0.03, 0.01])       # N m: a smooth motion, no spin-up
    d.qvel[:6] = [0.3, -0.2, 2.0, 0.4, -0.3, 0.5]
    S = int(round(seconds / m.opt.timestep))
    out = np.empty((S, 14))
    assert m.nv == 13
    for k in range(S):
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[6:] = amp * np.sin(w * d.time + ph).sum(1) / 3       # between the links: the joints only
        out[k] = np.concatenate([[d.time], d.qpos])
        mujoco.mj_step(m, d)
    t = out[:, 0]
    assert np.all(np.diff(t) > 0), "MuJoCo reset its data: the flight went unstable"
    quat = Rotation.from_euler("XYZ", out[:, 4:7]).as_quat()[:, [3, 0, 1, 2]]       # R = Rx Ry Rz (E3)
    return model, t, out[:, 1:4], quat, out[:, 7:14]


def test_floating_base_in_flight(arm):
    """A floating arm in flight (MuJoCo, 3 s, no torques logged, positions with 1e-6 rad / 1e-6 m noise) is
    identified from its base rows with its heaviest mass combination known (E97): every H positive definite
    after the consistent fit; the identifiable combinations within their 95% intervals (measured: all 59,
    largest 1.82 standard deviations). Planted wrong once each (by hand): without the known mass (the root's
    mass column zeroed instead) the fit returned zeros for the root link, 25% covered; with the base
    coordinates' own damping, friction and offsets as parameters (ParameterSet's default) 84% covered."""
    from urdf2links.identification import ParameterSet
    from urdf2links.identification.floating import identify_floating
    from urdf2links.robot_logs import RobotLog, check_log, derivatives
    from urdf2links.robot_logs.base import BasePoses

    NOISE = 1e-6       # rad and m: a fine encoder; at 1e-5 the regressor's own noise biases the fit (78% covered)
    model, t, pos, quat, q = _flight(arm["urdf"])
    t = np.round(t, 9)
    rng = np.random.default_rng(11)
    names = tuple(model.coordinate_names[6:])
    poses = BasePoses(source="columns", frame="world", times=t, positions=pos + NOISE * rng.standard_normal(pos.shape),
                      quaternions=quat, rows=np.arange(1, len(t) + 1))
    log = RobotLog(times=np.round(t, 9), names=names, positions=q + NOISE * rng.standard_normal(q.shape),
                   velocities=np.full_like(q, np.nan), efforts=np.full_like(q, np.nan), source="flight", base=poses)
    log = check_log(log, joints=names)
    d = derivatives(log, order=5)
    params = ParameterSet.from_model(model, joints=())      # links only: the base rows see no joint term
    res = identify_floating(params, d)
    truth = res.base.beta(params.values)
    z = np.where(res.fit.std > 0, (res.fit.beta - truth) / np.where(res.fit.std > 0, res.fit.std, 1), 0.0)
    print(f"floating: {res.base.r} base parameters, condition {res.fit.condition_number:.3g}, covered "
          f"{np.mean(res.fit.covers(truth)):.3f}, max |z| {np.max(np.abs(z)):.2f}, min eig {np.min(res.eig):.3g}")
    assert np.all(res.eig > 0)
    assert np.mean(res.fit.covers(truth)) >= 0.95          # measured 1.0 (59 of 59)
    assert np.max(np.abs(z)) < 3.0                          # measured 1.82
