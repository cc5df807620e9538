"""MuJoCo's own system-identification toolbox (``mujoco.sysid``, the ``sysid`` extra) and ours on the same log.

The robot: example-robot-data's Panda arm (fingers welded, 7 joints) with parameters planted in its MJCF twin
(``mjcf_from_model``: the library's frames and H at full precision): ``panda_link3`` mass x 1.2, ``panda_joint2``
damping 0.5, ``panda_joint4`` armature 0.05. A motor per joint and a position sensor per joint are added. The
log: MuJoCo (semi-implicit Euler, 1 ms) driven by the computed torques of a sum-of-sines trajectory, replayed
by ``mujoco.rollout`` (the recorded torques as controls: the same motion); noise as issue 47 asks (positions 1e-4 rad, efforts 1% of their range).

- **MuJoCo's toolbox**: ``sysid.optimize`` (its Gauss-Newton on rollouts, finite-difference Jacobians) of the
  three planted parameters, from the description's values, with the logged (noisy) efforts as controls and
  the logged positions as the sensors;
- **ours**: ``identify_log`` (every link and joint parameter: 10 per link, 4 per joint; the base parameters,
  weighted least squares, E96) on the same log.

Timed once each (wall clock, after a warm-up of the compiled code for ours; MuJoCo's compiles nothing). Writes
``reports/benchmarks/identify_vs_mujoco_sysid.md`` and the table in docs/identify.md's section is that file.

Usage::

    python benchmarks/identify_vs_mujoco_sysid.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

PLANTED = {"m_panda_link3": ("mass x 1.2", None), "damping_panda_joint2": ("0.5", 0.5),
           "armature_panda_joint4": ("0.05", 0.05)}


def _models(folder: Path):
    from lxml import etree

    from test_identify_logs import _arm_urdf, _params
    from corpus import NAMED, path as corpus_path

    root = etree.fromstring(corpus_path(NAMED["panda"]).read_bytes())
    for j in root.findall("joint"):
        if j.get("name") in ("panda_finger_joint1", "panda_finger_joint2"):
            j.set("type", "fixed")
            for c in list(j):
                if c.tag in ("mimic", "limit", "axis", "dynamics"):
                    j.remove(c)
    desc_urdf = folder / "panda_arm.urdf"
    desc_urdf.write_text(etree.tostring(root, encoding="unicode"))
    planted = _arm_urdf(folder / "panda_planted.urdf")
    return desc_urdf, planted, _params(desc_urdf), _params(planted)


def _spec(model, damping, armature):
    """The MJCF twin as an MjSpec with motors and position sensors; damping and armature by joint name."""
    import mujoco
    from lxml import etree

    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model

    root = etree.fromstring(mjcf_from_model(model, gravity=model.gravity_vector).xml.encode())
    root.find("option").remove(root.find("option").find("flag"))
    for j in root.find("worldbody").iter("joint"):
        j.set("damping", repr(float(damping.get(j.get("name"), 0.0))))
        j.set("armature", repr(float(armature.get(j.get("name"), 0.0))))
    act, sen = etree.SubElement(root, "actuator"), etree.SubElement(root, "sensor")
    for c in model.coordinate_names:
        etree.SubElement(act, "motor", name=f"{c}_motor", joint=c, gear="1")
        etree.SubElement(sen, "jointpos", name=f"{c}_pos", joint=c)
    return mujoco.MjSpec.from_string(etree.tostring(root, encoding="unicode"))


def _log(spec, names, limits, seconds, seed=5):
    """Computed torques along sums of sines (the planted model's M and bias), replayed by mujoco.rollout."""
    import mujoco
    import mujoco.rollout as rollout

    m = spec.compile()
    m.opt.timestep = 1e-3
    d = mujoco.MjData(m)
    lo, hi = np.array([limits[c][0] for c in names]), np.array([limits[c][1] for c in names])
    mid, amp = 0.5 * (lo + hi), np.minimum(0.3 * (hi - lo), 1.0)
    f = np.array([0.1, 0.23, 0.37, 0.61, 0.9])
    rng = np.random.default_rng(47)
    phase, a = rng.uniform(0, 2 * np.pi, (7, 5)), rng.uniform(0.5, 1, (7, 5)) / np.arange(1, 6) ** 0.5
    a /= a.sum(1, keepdims=True)
    w = 2 * np.pi * f
    S = int(round(seconds / 1e-3))
    t = np.arange(S) * 1e-3
    qr = mid + amp * np.einsum("jk,sjk->sj", a, np.sin(w * t[:, None, None] + phase))
    vr = amp * np.einsum("jk,sjk->sj", a * w, np.cos(w * t[:, None, None] + phase))
    ar = -amp * np.einsum("jk,sjk->sj", a * w ** 2, np.sin(w * t[:, None, None] + phase))
    tau = np.empty((S, 7))
    M = np.empty((7, 7))
    d.qpos[:], d.qvel[:] = qr[0], vr[0]
    for k in range(S):                # computed torque with a servo (MuJoCo's own M, bias, damping), recorded
        mujoco.mj_forward(m, d)
        mujoco.mj_fullM(m, d, M)
        acc = ar[k] + 100.0 * (qr[k] - d.qpos) + 20.0 * (vr[k] - d.qvel)
        tau[k] = M @ acc + d.qfrc_bias + m.dof_damping * d.qvel
        d.ctrl[:] = tau[k]
        mujoco.mj_step(m, d)
    mujoco.mj_resetData(m, d)
    d.qpos[:], d.qvel[:] = qr[0], vr[0]
    from mujoco import sysid

    x0 = sysid.create_initial_state(m, d.qpos, d.qvel, d.act)
    state, sensor = rollout.rollout(m, d, x0, tau[:-1])
    state, sensor = np.squeeze(state, 0), np.squeeze(sensor, 0)
    rng = np.random.default_rng(seed)
    q = sensor + 1e-4 * rng.standard_normal(sensor.shape)
    tau_n = tau + 0.01 * np.ptp(tau, axis=0) * rng.standard_normal(tau.shape)
    return x0, t, state[:, 0], q, tau_n, m


def _set_damping(spec, p) -> None:
    """MuJoCo 4's joint damping is an array (its first entry the linear coefficient)."""
    j = spec.joint("panda_joint2")
    v = np.array(j.damping, float).reshape(-1)
    v[0] = p.value[0]
    j.damping = v


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks" / "identify_vs_mujoco_sysid.md"))
    args = ap.parse_args(argv)
    import tempfile

    from urdf2links.parsers.robot_file import load_robot
    from urdf2links.robot_logs import RobotLog, angular_limits, check_log, derivatives
    from urdf2links.identification.from_log import identify_log

    folder = Path(tempfile.mkdtemp())
    desc_urdf, planted_urdf, (dparts, dmodel, desc), (pparts, pmodel, truth) = _models(folder)
    names = tuple(dmodel.coordinate_names)
    tv = truth.values.copy()
    tv[truth.index("armature_panda_joint4")] = 0.05
    pdamp = {j.name: j.damping for j, _b in pparts.joints}
    ddamp = {j.name: j.damping for j, _b in dparts.joints}
    limits = angular_limits(load_robot(desc_urdf))
    spec = _spec(pmodel, pdamp, {"panda_joint4": 0.05})
    x0, t, times, q, tau, m = _log(spec, names, limits, args.seconds)
    rows = [f"# Identification: MuJoCo's sysid toolbox and ours on the same log\n",
            f"Generated by `benchmarks/identify_vs_mujoco_sysid.py --seconds {args.seconds:g}` "
            f"(Panda arm, {len(t)} samples at 1 kHz, noise 1e-4 rad / 1% of effort range).\n"]
    # ours
    k0 = int(round(times[0] / 1e-3))               # the rollout's sensors: after each step (time k0 ms on)
    log = RobotLog(times=np.round(times, 9), names=names, positions=q, velocities=np.full_like(q, np.nan),
                   efforts=tau[k0:k0 + len(times)], source="benchmark")
    identify_log(desc, derivatives(check_log(log, joints=names), order=5))       # warm the compiled code
    t0 = time.perf_counter()
    li = identify_log(desc, derivatives(check_log(log, joints=names), order=5))
    ours_s = time.perf_counter() - t0
    ours = {}
    for nm in PLANTED:
        k = desc.index(nm)
        a = np.flatnonzero(li.base.independent == k)
        alone = a.size and not np.any(li.base.K[a[0]] != 0)
        ours[nm] = (li.values[k], li.acceleration.std[a[0]] if alone else None, bool(alone), li.base.names[a[0]] if a.size else None)
    # MuJoCo's toolbox
    try:
        from mujoco import sysid
    except ImportError as err:
        sysid = None
        why = f"mujoco.sysid cannot be imported here ({err}): pip install 'mujoco[sysid]'"
    theirs, sys_s = {}, None
    if sysid is not None:
        dspec = _spec(dmodel, ddamp, {})
        params = sysid.ParameterDict()
        m3 = float(desc.values[desc.index("m_panda_link3")])
        params.add(sysid.Parameter("m_panda_link3", nominal=m3, min_value=0.3 * m3, max_value=3 * m3,
                                   modifier=lambda s, p: setattr(s.body("panda_link3"), "mass", p.value[0])))
        params.add(sysid.Parameter("damping_panda_joint2", nominal=ddamp["panda_joint2"], min_value=0.0, max_value=5.0,
                                   modifier=_set_damping))
        params.add(sysid.Parameter("armature_panda_joint4", nominal=0.0, min_value=0.0, max_value=1.0,
                                   modifier=lambda s, p: setattr(s.joint("panda_joint4"), "armature", p.value[0])))
        control_ts = sysid.TimeSeries(t, tau)
        sensor_ts = sysid.TimeSeries.from_names(times, q, m)
        ms = sysid.ModelSequences("panda", dspec, "log", x0, control_ts, sensor_ts)
        t0 = time.perf_counter()
        residual_fn = sysid.build_residual_fn(models_sequences=[ms])
        opt, _res = sysid.optimize(initial_params=params, residual_fn=residual_fn, optimizer="mujoco", verbose=False)
        sys_s = time.perf_counter() - t0
        theirs = {nm: float(opt[nm].value[0]) for nm in PLANTED}
    rows.append("| parameter | truth | MuJoCo sysid | its error | ours | ours: std / identifiable | our error |")
    rows.append("|---|---|---|---|---|---|---|")
    for nm in PLANTED:
        tr = float(tv[truth.index(nm)])
        th = theirs.get(nm)
        v, s, alone, combo = ours[nm]
        ours_txt = (f"{v:.5g}" if alone else "kept at the description")
        ident = (f"{s:.2g}, alone" if alone else f"only in `{combo[:60]}`" if combo else "not identifiable: kept")
        rows.append(f"| {nm} | {tr:.5g} | {'n/a' if th is None else f'{th:.5g}'} | "
                    f"{'n/a' if th is None else f'{abs(th - tr) / max(abs(tr), 1e-12):.1%}'} | {ours_txt} | {ident} | "
                    f"{f'{abs(v - tr) / max(abs(tr), 1e-12):.1%}' if alone else '-'} |")
    rows.append("")
    rows.append(f"Wall time: ours {ours_s:.3f} s (every parameter: {desc.p}, {li.base.r} base combinations); "
                + (f"MuJoCo's toolbox {sys_s:.3f} s (3 parameters); ratio {sys_s / ours_s:.1f}x." if sys_s else why))
    n_comb = li.base.r
    bt = li.base.beta(tv)
    rows.append(f"\nOurs on all {n_comb} base combinations: {np.mean(li.acceleration.covers(bt)):.0%} of the 95% intervals "
                f"hold the truth; median |error| / std {np.median(np.abs(li.acceleration.beta - bt) / li.acceleration.std):.2f}.")
    text = "\n".join(rows) + "\n"
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
