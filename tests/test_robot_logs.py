"""A real robot's log (urdf2links.robot_logs, docs/logs.md): read from CSV, NPZ and ROS 2 bags, checked
with named errors, differentiated by a stated filter.

The log: MuJoCo simulates the Panda of example-robot-data (its URDF through MuJoCo's own importer),
tracking a sum of sines by computed torque (MuJoCo's own M and bias); noise is added as the issue asks
(positions 1e-4 rad, efforts 1% of each joint's range; velocities as MuJoCo gives them). It is written
as a ROS 2 bag (MCAP, and sqlite3) by rosbags' writer, and as CSV and NPZ, and read back equal.
Each bad-data case is planted in that log and must raise its named error, which names the column (or
topic) and the row; the clean log must pass every check (the false-positive side of each).
"""

from __future__ import annotations

import csv
import sys

import numpy as np
import pytest

from corpus import NAMED, path as corpus_path
from urdf2links.parsers.robot_file import load_robot
from urdf2links.robot_logs import (BasePoses, DegreesError, JumpError, LogError, LogFormatError, NonFiniteError,
                                   NonUniformError, RobotLog, TimeOrderError, TooFewSamplesError, UnknownJointError,
                                   Wrenches, angular_limits, check_log, check_samples, derivatives, noise_level,
                                   read_log, write_csv, write_npz)
from urdf2links.robot_logs.bags import JOINT_STATE, WRENCH_STAMPED
from urdf2links.robot_logs.base import base_coordinates

ARM = tuple(f"panda_joint{i}" for i in range(1, 8))
SEED = 47


# -- the simulated log ---------------------------------------------------------------------------------
def _simulate_panda(seconds: float = 3.0):
    """(description joint names, limits, times (S,), q, qd, tau (S, 7)) of MuJoCo tracking sines by
    computed torque (its own M and bias), noiseless."""
    import mujoco
    from urdf2links.compare.mujoco_side.mujoco_urdf import mujoco_from_urdf

    mj = mujoco_from_urdf(corpus_path(NAMED["panda"]))
    m = mj.model
    m.opt.timestep = 1e-3
    d = mujoco.MjData(m)
    lo, hi = m.jnt_range[:7, 0], m.jnt_range[:7, 1]
    mid, amp = 0.5 * (lo + hi), np.minimum(0.25 * (hi - lo), 0.6)
    f = np.array([0.2, 0.5, 1.1])
    phase = np.random.default_rng(SEED).uniform(0, 2 * np.pi, (7, 3))

    def ref(t):
        w = 2 * np.pi * f
        return (mid + amp * np.sin(w * t + phase).sum(1) / 3, amp * (w * np.cos(w * t + phase)).sum(1) / 3,
                -amp * (w**2 * np.sin(w * t + phase)).sum(1) / 3)
    d.qpos[:7], d.qvel[:7], _ = ref(0.0)
    S = int(round(seconds / m.opt.timestep))
    out = np.empty((S, 1 + 21))
    M = np.empty((m.nv, m.nv))
    for k in range(S):
        mujoco.mj_forward(m, d)
        mujoco.mj_fullM(m, d, M)
        qr, vr, ar = ref(d.time)
        acc = np.zeros(m.nv)
        acc[:7] = ar + 100.0 * (qr - d.qpos[:7]) + 20.0 * (vr - d.qvel[:7])     # computed torque
        acc[7:] = -100.0 * d.qpos[7:] - 20.0 * d.qvel[7:]                           # fingers held
        tau = M @ acc + d.qfrc_bias
        d.qfrc_applied[:] = tau
        out[k] = np.concatenate([[d.time], d.qpos[:7], d.qvel[:7], tau[:7]])
        mujoco.mj_step(m, d)
    assert np.all(np.diff(out[:, 0]) > 0), "MuJoCo reset its data: the run went unstable"
    limits = {n: (float(a), float(b)) for n, a, b in zip(mj.joint_names, m.jnt_range[:, 0], m.jnt_range[:, 1])}
    return mj.joint_names, limits, out[:, 0], out[:, 1:8], out[:, 8:15], out[:, 15:22]


@pytest.fixture(scope="module")
def panda(corpus_installed):
    """The noisy log (a RobotLog in memory), the description's joint names and limits."""
    names, limits, t, q, qd, tau = _simulate_panda()
    rng = np.random.default_rng(SEED)
    q = q + 1e-4 * rng.standard_normal(q.shape)
    tau = tau + 0.01 * np.ptp(tau, axis=0) * rng.standard_normal(tau.shape)
    log = RobotLog(times=np.round(t, 9), names=ARM, positions=q, velocities=qd, efforts=tau, source="simulated")
    return log, names, limits


def _write_bag(path, log: RobotLog, *, storage: str = "mcap", topic: str = "/joint_states", wrench=None,
               names_of=None):
    """``log`` as a rosbag2 folder written by rosbags' own writer (JointState per sample, stamps in ns;
    ``wrench`` (S, 6) on /wrench as WrenchStamped; ``names_of(k)`` overrides message k's names)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    t0 = 1_700_000_000 * 10**9
    stamps = t0 + np.round(log.times * 1e9).astype(np.int64)
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conn = w.add_connection(topic, JOINT_STATE, typestore=ts)
        wconn = None if wrench is None else w.add_connection("/wrench", WRENCH_STAMPED, typestore=ts)
        for k, s in enumerate(stamps):
            header = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=int(s // 10**9),
                                                                                    nanosec=int(s % 10**9)),
                                              frame_id="base")
            names = list(log.names) if names_of is None else names_of(k)
            msg = T[JOINT_STATE](header=header, name=names, position=log.positions[k].copy(),
                                 velocity=log.velocities[k].copy(), effort=log.efforts[k].copy())
            w.write(conn, int(s), ts.serialize_cdr(msg, JOINT_STATE))
            if wconn is not None:
                V3 = T["geometry_msgs/msg/Vector3"]
                wr = T["geometry_msgs/msg/Wrench"](force=V3(*wrench[k, :3]), torque=V3(*wrench[k, 3:]))
                w.write(wconn, int(s), ts.serialize_cdr(T[WRENCH_STAMPED](header=header, wrench=wr), WRENCH_STAMPED))
    return stamps


def _same(a: RobotLog, b: RobotLog, *, times_exact: bool = True):
    assert a.names == b.names
    for q in ("positions", "velocities", "efforts"):
        np.testing.assert_array_equal(getattr(a, q), getattr(b, q), err_msg=q)
    if times_exact:
        np.testing.assert_array_equal(a.times, b.times)


def test_without_rosbags_the_error_names_the_extra(panda, tmp_path, monkeypatch):
    """rosbags is optional (the logs extra): without it, a bag is refused by a LogFormatError that says
    what to install (its import blocked here as an uninstalled package would be)."""
    log, _, _ = panda
    _write_bag(tmp_path / "bag", log.take(slice(0, 5)))
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    with pytest.raises(LogFormatError) as e:
        read_log(tmp_path / "bag")
    assert "urdf2links[logs]" in str(e.value)


# -- round trips -------------------------------------------------------------------------------------
def test_mcap_bag_round_trip(panda, tmp_path):
    """The MCAP bag written by rosbags' writer reads back equal: every position, velocity and effort
    bit for bit (CDR float64), the stamps to the nanosecond (they are integers), and the wrench topic."""
    log, _, _ = panda
    wrench = np.random.default_rng(SEED).normal(size=(log.n_samples, 6))
    stamps = _write_bag(tmp_path / "bag", log, wrench=wrench)
    back = read_log(tmp_path / "bag", wrench_topic="/wrench")
    _same(log, back, times_exact=False)
    assert back.t0_ns == stamps[0]
    np.testing.assert_array_equal(back.t0_ns + np.round(back.times * 1e9).astype(np.int64), stamps)
    np.testing.assert_array_equal(back.wrenches.values, wrench)
    assert back.wrenches.frame == "base" and back.row_word == "message" and back.topic == "/joint_states"
    said = back.describe()
    assert f"{log.n_samples} samples" in said and "7 with effort" in said and "/wrench" in said
    d = derivatives(back)                       # the wrenches at the joints' times, through the same filter
    assert d.wrenches.shape == (log.n_samples, 6)
    np.testing.assert_allclose(d.wrenches, derivatives(back.with_changes(
        positions=wrench, velocities=wrench, efforts=wrench, names=tuple("abcdef"))).positions, atol=1e-12)
    # the .mcap file inside the folder names the same bag
    mcap = next((tmp_path / "bag").glob("*.mcap"))
    _same(back, read_log(mcap))


def test_sqlite_bag_round_trip(panda, tmp_path):
    log, _, _ = panda
    short = log.take(slice(0, 300))
    _write_bag(tmp_path / "bag", short, storage="sqlite3", topic="/franka/joint_states")
    _same(short, read_log(tmp_path / "bag", topic="/franka/joint_states"), times_exact=False)


def test_csv_and_npz_round_trip(panda, tmp_path):
    """CSV (17 significant digits) and NPZ read back bit for bit, times included. Planted wrong case
    (checked once): write_csv with 15 significant digits fails here."""
    log, _, _ = panda
    _same(log, read_log(write_csv(log, tmp_path / "log.csv")))
    _same(log, read_log(write_npz(log, tmp_path / "log.npz")))


def test_csv_column_variants(panda, tmp_path):
    """The variants docs/logs.md lists read as the canonical names; an unknown column is noted, not read."""
    log, _, _ = panda
    short = log.take(slice(0, 50))
    forms = ["position[{j}]", "{j}_vel", "tau_{j}"]
    header = ["time"] + [f.format(j=j) for j in short.names for f in forms] + ["comment"]
    rows = [[repr(float(t))] + [repr(float(x)) for j in range(7)
                                for x in (short.positions[k, j], short.velocities[k, j], short.efforts[k, j])] + ["x"]
            for k, t in enumerate(short.times)]
    p = tmp_path / "variants.csv"
    with open(p, "w", newline="") as f:
        csv.writer(f).writerows([header, *rows])
    back = read_log(p)
    _same(short, back)
    assert back.column("effort", 2) == "tau_panda_joint3"
    assert any("comment" in n for n in back.notes)
    cols = {"t_ns": np.round(short.times * 1e9).astype(np.int64)}        # NPZ, one array per column
    cols.update({f"{j}/position": short.positions[:, i] for i, j in enumerate(short.names)})
    np.savez(tmp_path / "columns.npz", **cols)
    back = read_log(tmp_path / "columns.npz")
    np.testing.assert_array_equal(back.positions, short.positions)
    np.testing.assert_allclose(back.times, short.times, rtol=0, atol=1e-15)
    assert not any(back.logged("effort")) and any("nanoseconds" in n for n in back.notes)


def test_segment(panda, tmp_path):
    log, _, _ = panda
    p = write_csv(log, tmp_path / "log.csv")
    seg = read_log(p, t_from=1.0, t_to=2.0)
    assert seg.times[0] >= 1.0 and seg.times[-1] <= 2.0 and seg.n_samples == 1001
    assert seg.rows[0] == 1001                      # the file's own row, kept
    with pytest.raises(LogFormatError) as e:
        read_log(p, t_from=10.0)
    assert "runs from" in str(e.value)


# -- the clean log passes ------------------------------------------------------------------------------
def test_clean_log_passes_every_check(panda):
    """The noisy simulated log raises nothing (no jump, no degrees), keeps the description's order and
    notes the fingers it lacks; this is the false-positive side of every bad-data test below."""
    log, names, limits = panda
    checked = check_log(log, joints=names, limits=limits, n_base=50)
    assert checked.names == ARM
    assert any("panda_finger_joint1" in n for n in checked.notes)
    np.testing.assert_array_equal(checked.positions, log.positions)
    # the same with the names and limits of urdf2links' own model of the description, as identify reads them
    model = load_robot(corpus_path(NAMED["panda"]))
    assert angular_limits(model) == {n: limits[n] for n in ARM}
    assert check_log(log, joints=model.coordinate_names, limits=angular_limits(model)).names == ARM


# -- bad data: each case planted in the log, each with its named error -----------------------------------
def _csv_with(log: RobotLog, tmp_path, edit) -> str:
    """The log as CSV with ``edit(header, rows)`` applied to its cells (strings)."""
    p = write_csv(log, tmp_path / "log.csv")
    with open(p, newline="") as f:
        header, *rows = list(csv.reader(f))
    edit(header, rows)
    with open(p, "w", newline="") as f:
        csv.writer(f).writerows([header, *rows])
    return p


@pytest.mark.parametrize("cell, error", [("", "nan"), ("inf", "inf"), ("-inf", "inf")])
def test_non_finite_value_is_named(panda, tmp_path, cell, error):
    log, names, limits = panda
    col = "panda_joint3.effort"

    def edit(header, rows):
        rows[1234][header.index(col)] = cell
    checked = read_log(_csv_with(log, tmp_path, edit))
    with pytest.raises(NonFiniteError) as e:
        check_log(checked, joints=names, limits=limits)
    assert (e.value.column, e.value.row) == (col, 1235)
    assert e.value.time == pytest.approx(log.times[1234])


def test_a_jump_is_named_and_a_wrap_is_unwrapped(panda, tmp_path):
    """A step of 0.3 rad from row 2001 on is a JumpError at that row; the same joint shifted to cross
    pi and wrapped into (-pi, pi] is unwrapped and noted, back to the shifted values (to rounding).
    Planted wrong case (checked once): with the step's departure from its neighbours set to zero in
    check_jumps, no JumpError is raised and this fails."""
    log, names, limits = panda
    P = log.positions.copy()
    P[2000:, 4] += 0.3
    with pytest.raises(JumpError) as e:
        check_log(log.with_changes(positions=P), joints=names)
    assert (e.value.column, e.value.row) == ("panda_joint5.position", 2001)
    assert e.value.step == pytest.approx(0.3, abs=0.01)

    shifted = log.positions.copy()
    shifted[:, 0] += np.pi - np.median(shifted[:, 0])         # joint 1 oscillates around pi
    wrapped = shifted.copy()
    wrapped[:, 0] = np.angle(np.exp(1j * wrapped[:, 0]))
    assert np.ptp(wrapped[:, 0]) > 6.0                         # it does wrap
    checked = check_log(log.with_changes(positions=wrapped), joints=names)
    np.testing.assert_allclose(checked.positions[:, 0] - checked.positions[0, 0] + shifted[0, 0],
                               shifted[:, 0], atol=1e-12)
    assert any("unwrapped" in n and "panda_joint1.position" in n for n in checked.notes)


@pytest.mark.parametrize("kind", ["unsorted", "duplicate"])
def test_time_stamps_out_of_order(panda, tmp_path, kind):
    log, _, _ = panda

    def edit(header, rows):
        if kind == "unsorted":
            rows[700][0], rows[701][0] = rows[701][0], rows[700][0]
        else:
            rows[701][0] = rows[700][0]
    with pytest.raises(TimeOrderError) as e:
        read_log(_csv_with(log, tmp_path, edit))
    assert (e.value.kind, e.value.column, e.value.row) == (kind, "t", 702)


def test_time_stamps_in_a_bag(panda, tmp_path):
    """A bag whose header stamps repeat: the error names the topic and the message."""
    log, _, _ = panda
    t = log.times[:100].copy()
    t[40] = t[39]
    _write_bag(tmp_path / "bag", log.take(slice(0, 100)).with_changes(times=t))
    with pytest.raises(TimeOrderError) as e:
        read_log(tmp_path / "bag")
    assert (e.value.kind, e.value.topic, e.value.row) == ("duplicate", "/joint_states", 41)


def test_unknown_joint_with_did_you_mean(panda, tmp_path):
    log, names, _ = panda

    def edit(header, rows):
        for c, h in enumerate(header):
            header[c] = h.replace("panda_joint4", "panda_jiont4")
    with pytest.raises(UnknownJointError) as e:
        check_log(read_log(_csv_with(log, tmp_path, edit)), joints=names)
    assert e.value.unknown == ("panda_jiont4",)
    assert e.value.suggestions["panda_jiont4"][0] == "panda_joint4"
    assert e.value.column == "panda_jiont4.position" and "did you mean 'panda_joint4'" in str(e.value)


def test_degrees_are_named(panda):
    """Positions in degrees (beyond the limits, within them once converted) and velocities in degrees per
    second (180/pi times the positions' derivative) each raise DegreesError on their column."""
    log, names, limits = panda
    deg = 180 / np.pi
    P = log.positions.copy()
    P[:, 1] *= deg
    with pytest.raises(DegreesError) as e:
        check_log(log.with_changes(positions=P), joints=names, limits=limits)
    assert e.value.column == "panda_joint2.position" and e.value.factor == pytest.approx(deg)
    with pytest.raises(DegreesError) as e:          # without limits, the rates still tell
        check_log(log.with_changes(positions=P), joints=names)
    assert e.value.column == "panda_joint2.position" and e.value.factor == pytest.approx(deg, rel=0.02)
    V = log.velocities.copy()
    V[:, 5] *= deg
    with pytest.raises(DegreesError) as e:
        check_log(log.with_changes(velocities=V), joints=names, limits=limits)
    assert e.value.column == "panda_joint6.velocity" and e.value.factor == pytest.approx(deg, rel=0.02)


def test_too_few_samples(panda):
    log, names, _ = panda
    short = log.take(slice(0, 5))
    with pytest.raises(TooFewSamplesError) as e:
        check_log(short, joints=names, n_base=50)
    assert (e.value.equations, e.value.needed) == (35, 51)
    check_samples(log.take(slice(0, 8)), n_base=50)                     # 56 equations: enough
    with pytest.raises(TooFewSamplesError) as e:                         # a floating base's 6 rows, no efforts
        check_samples(log.take(slice(0, 8)), n_base=50, equations_per_sample=6)
    assert e.value.equations == 48


def test_bag_topic_errors(panda, tmp_path):
    """A missing topic, a topic of another type, and a topic whose messages name other joints."""
    log, _, _ = panda
    short = log.take(slice(0, 20))
    _write_bag(tmp_path / "bag", short, wrench=np.zeros((20, 6)))
    with pytest.raises(LogFormatError) as e:
        read_log(tmp_path / "bag", topic="/joint_state")
    assert e.value.topic == "/joint_state" and "/joint_states" in str(e.value)
    with pytest.raises(LogFormatError) as e:
        read_log(tmp_path / "bag", topic="/wrench")
    assert e.value.topic == "/wrench" and WRENCH_STAMPED in str(e.value)

    def names_of(k):
        return list(ARM) if k != 12 else list(ARM[::-1])
    _write_bag(tmp_path / "mixed", short, names_of=names_of)
    with pytest.raises(LogFormatError) as e:
        read_log(tmp_path / "mixed")
    assert (e.value.topic, e.value.row) == ("/joint_states", 13)


# -- derivatives ----------------------------------------------------------------------------------------
A = np.array([0.5, 0.2, 0.1])
F = np.array([0.3, 1.1, 2.7])
SIGMA = 1e-4


def _sines(fs=1000.0, seconds=6.0, seed=SEED):
    t = np.arange(0, seconds, 1 / fs)
    w = 2 * np.pi * F[:, None]
    q = (A[:, None] * np.sin(w * t)).sum(0)
    exact = [q, (A[:, None] * w * np.cos(w * t)).sum(0), -(A[:, None] * w**2 * np.sin(w * t)).sum(0)]
    noisy = q + SIGMA * np.random.default_rng(seed).standard_normal(len(t))
    nan = np.full((len(t), 1), np.nan)
    return RobotLog(times=t, names=("j",), positions=noisy[:, None], velocities=nan, efforts=nan,
                    source="sum of sines"), exact


def _bound(d, k: int) -> float:
    """The error bound of derivative ``k`` in the interior: the filter's bias on each sine,
    ``A_i w_i^k |1 - G_k(f_i)|`` (exact for a zero-phase linear filter, from its gains E93, E94), plus
    5 standard deviations of the filtered white noise, ``5 sigma ||h_k||_2``, where ``h_k`` is the filter's
    response to a unit impulse (the filter is linear): a Gaussian exceeds 5 sigma with probability 6e-7
    a sample, 4e-3 over the 6,000 samples (and the seed is fixed)."""
    bias = float(np.sum(A * (2 * np.pi * F) ** k * np.abs(1 - d.filter.gains(F, orders=(k,))[0])))
    from urdf2links.robot_logs import filters
    S = len(d.times)
    imp = np.zeros((S, 1))
    imp[S // 2] = 1.0
    h = filters.apply(d.filter, d.times, imp)[k][:, 0]
    return bias + 5 * SIGMA * float(np.linalg.norm(h))


@pytest.mark.parametrize("method", ["savgol", "spline"])
def test_filtered_derivatives_error_is_bounded(method):
    """Velocity and acceleration errors on a sum of sines with 1e-4 noise stay within the stated bound
    (_bound) in the interior, and the bound is not loose (the error reaches a third of it). Planted wrong
    case (checked once): a derivative 2% off (a wrong time step) exceeds the velocity bound."""
    log, exact = _sines()
    d = derivatives(log, method=method)
    i = d.interior
    for k, got in ((1, d.velocities), (2, d.accelerations)):
        err = np.abs(got[i, 0] - exact[k][i]).max()
        bound = _bound(d, k)
        assert err <= bound, (k, err, bound)
        assert err >= bound / 3, (k, err, bound)
    assert np.abs(1.02 * d.velocities[i, 0] - exact[1][i]).max() > _bound(d, 1)


@pytest.mark.parametrize("method", ["savgol", "spline"])
def test_bandwidth_is_the_measured_minus_3_db(method):
    """A sine at the stated bandwidth comes out of the smoother at 1/sqrt 2 of its amplitude (to 0.2%:
    the savgol bandwidth is found on a grid of fs/8192, the spline's (E93) is the continuous limit)."""
    log, _ = _sines()
    d = derivatives(log, method=method)
    s = np.sin(2 * np.pi * d.bandwidth_hz * log.times)
    one = log.with_changes(positions=s[:, None])
    kw = dict(window=d.filter.window) if method == "savgol" else dict(cutoff_hz=d.bandwidth_hz)
    out = derivatives(one, method=method, **kw)
    assert np.abs(out.positions[out.interior, 0]).max() == pytest.approx(1 / np.sqrt(2), rel=2e-3)


def test_noise_level_and_stated_filter(tmp_path):
    """The third-difference estimate (E95) finds the planted 1e-4 (to 5%: the MAD of 6,000 samples has
    a relative spread near 1.3%); the filter is stated with its bandwidth, and the figure is written."""
    log, _ = _sines()
    assert noise_level(log.positions)[0] == pytest.approx(SIGMA, rel=0.05)
    d = derivatives(log)
    text = d.describe()
    assert "Savitzky-Golay" in text and f"{d.bandwidth_hz:.4g} Hz" in text
    assert d.filter.window % 2 == 1 and abs(d.bandwidth_hz - 10.0) < 0.5
    png = d.plot(tmp_path / "filter.png")
    assert png.stat().st_size > 10_000


def test_uneven_sampling_refused_by_savgol(panda):
    """Savitzky-Golay refuses steps more than 1% off the median (naming the row); the spline takes them."""
    log, _, _ = panda
    t = log.times.copy()
    t[500:] += 0.0005
    uneven = log.with_changes(times=t)
    with pytest.raises(NonUniformError) as e:
        derivatives(uneven)
    assert e.value.row == 501 and e.value.jitter == pytest.approx(0.5, rel=1e-3)
    d = derivatives(uneven, method="spline")
    assert np.isfinite(d.accelerations).all()
    P = uneven.positions.copy()
    P[:, 2] = np.nan                                # a joint without positions stays NaN, the rest filtered
    d = derivatives(uneven.with_changes(positions=P), method="spline")
    assert np.isnan(d.velocities[:, 2]).all() and np.isfinite(np.delete(d.velocities, 2, axis=1)).all()
    with pytest.raises(TooFewSamplesError):
        derivatives(log.take(slice(0, 8)))


def test_panda_derivatives_match_mujoco_velocities(panda, tmp_path):
    """On the simulated log, the filtered velocity matches MuJoCo's own qvel (logged without noise) to
    well under the noise-free signal: the bias of a 10 Hz filter on this sub-2 Hz motion plus the filtered
    noise, bounded here by 1% of the largest speed."""
    log, _, _ = panda
    d = derivatives(log)
    i = d.interior
    err = np.abs(d.velocities[i] - log.velocities[i]).max(axis=0)
    assert (err < 0.01 * np.abs(log.velocities).max(axis=0)).all(), err
    d.plot(tmp_path / "panda.png")


# -- a floating base's pose ----------------------------------------------------------------------------
def _base_motion(S=3000, dt=1e-3):
    """(times, the six floating coordinates (S, 6) and their rates (S, 6)) of sines in x, y, z and the ZYX
    angles; phi_z turns more than a full turn, so that its quaternions' angle wraps."""
    t = np.arange(S) * dt
    amp = np.array([0.3, 0.2, 0.1, 0.4, 0.5, 4.0])
    w = 2 * np.pi * np.array([0.5, 0.7, 0.9, 0.6, 0.4, 0.3])
    return t, amp * np.sin(w * t[:, None]), amp * w * np.cos(w * t[:, None])


def _quaternions(c):
    """(S, 4) w, x, y, z of R = Rx(phi_x) Ry(phi_y) Rz(phi_z), through urdf2links' own rotations."""
    from scipy.spatial.transform import Rotation
    from urdf2links.dynamics.rotations import xyz_angles_to_matrix

    xyzw = Rotation.from_matrix(np.array([xyz_angles_to_matrix(a) for a in c[:, 3:]])).as_quat()
    return np.column_stack([xyzw[:, 3], xyzw[:, :3]])


def test_base_pose_from_odometry_and_columns(panda, tmp_path):
    """A floating base's pose written as nav_msgs/Odometry by rosbags' writer, and as the base.* columns
    of a CSV, reads back as the six floating coordinates (ZYX angles unwrapped through phi_z's full turn)
    within 1e-9 of the planted ones, and their filtered rates within the filter's bias of the exact
    rates. Planted wrong case (checked once): with the quaternion's w, x, y, z left in ROS's x, y, z, w
    order the angles are wrong by far more than that."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    log, _, _ = panda
    t, c, cd = _base_motion()
    joints = log.take(slice(0, len(t)))
    quat = _quaternions(c)
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    with Writer(tmp_path / "bag", version=9, storage_plugin=StoragePlugin.MCAP) as w:
        cj = w.add_connection("/joint_states", JOINT_STATE, typestore=ts)
        co = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        for k, tk in enumerate(t):
            s = 10**9 + int(round(tk * 1e9))
            hdr = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=s // 10**9, nanosec=s % 10**9),
                                           frame_id="world")
            js = T[JOINT_STATE](header=hdr, name=list(ARM), position=joints.positions[k].copy(),
                                velocity=joints.velocities[k].copy(), effort=joints.efforts[k].copy())
            w.write(cj, s, ts.serialize_cdr(js, JOINT_STATE))
            pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](*c[k, :3]),
                                               orientation=T["geometry_msgs/msg/Quaternion"](*quat[k, 1:], quat[k, 0]))
            cov = np.zeros(36)
            odom = T["nav_msgs/msg/Odometry"](
                header=hdr, child_frame_id="base_link",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](
                    twist=T["geometry_msgs/msg/Twist"](linear=T["geometry_msgs/msg/Vector3"](0, 0, 0),
                                                       angular=T["geometry_msgs/msg/Vector3"](0, 0, 0)),
                    covariance=cov))
            w.write(co, s, ts.serialize_cdr(odom, "nav_msgs/msg/Odometry"))
    bag = read_log(tmp_path / "bag", base_topic="/odom")
    assert bag.base.frame == "world"
    table = joints.with_changes(times=t, base=BasePoses(source="columns", frame="", times=t, positions=c[:, :3],
                                                        quaternions=quat, rows=np.arange(1, len(t) + 1)))
    csv_back = read_log(write_csv(table, tmp_path / "base.csv"))
    for back in (bag, csv_back):
        d = derivatives(back)
        i = d.interior
        np.testing.assert_allclose(d.base[0][i], c[i], atol=2e-4)       # the smoother's bias on these sines
        np.testing.assert_allclose(base_coordinates(back.base, back.times), c, atol=1e-9)
        # rates: the filter's bias is |1 - G_1(f)| * amplitude * w, below 2e-3 of each rate's amplitude
        scale = np.abs(cd).max(axis=0)
        assert (np.abs(d.base[1][i] - cd[i]).max(axis=0) < 2e-3 * scale).all()


def test_base_pose_errors(panda, tmp_path):
    """A quaternion off unit norm is an error naming its row; a pitch within a degree of 90 degrees is an
    error naming its time (the ZYX rates are meaningless there)."""
    log, names, _ = panda
    t, c, _ = _base_motion(S=400)
    quat = _quaternions(c)
    short = log.take(slice(0, 400)).with_changes(times=t)
    Base = BasePoses
    bad = quat.copy()
    bad[123] *= 1.01
    with pytest.raises(LogError) as e:
        check_log(short.with_changes(base=Base("columns", "", t, c[:, :3], bad, np.arange(1, 401))), joints=names)
    assert e.value.row == 124 and e.value.column == "columns"
    c2 = c.copy()
    c2[:, 4] = np.linspace(1.0, 1.565, 400)                             # pitch up to 89.7 degrees
    tilted = short.with_changes(base=Base("columns", "", t, c2[:, :3], _quaternions(c2), np.arange(1, 401)))
    with pytest.raises(LogError) as e:
        derivatives(tilted)
    assert "pitch" in str(e.value) and e.value.time > t[300]


def test_side_topics_must_be_sorted(panda, tmp_path):
    """A wrench topic whose stamps repeat is a TimeOrderError naming the topic and the message, not a
    silently wrong interpolation. Planted wrong case: the same wrenches with increasing stamps pass."""
    log, _, _ = panda
    short = log.take(slice(0, 50))
    w = Wrenches(topic="/wrench", frame="", times=short.times.copy(), values=np.zeros((50, 6)))
    assert derivatives(short.with_changes(wrenches=w), window=11).wrenches.shape == (50, 6)
    t = short.times.copy()
    t[20] = t[19]
    with pytest.raises(TimeOrderError) as e:
        derivatives(short.with_changes(wrenches=Wrenches("/wrench", "", t, np.zeros((50, 6)))), window=11)
    assert (e.value.topic, e.value.row, e.value.kind) == ("/wrench", 21, "duplicate")
