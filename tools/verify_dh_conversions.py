#!/usr/bin/python3
"""Checks the published-geometry robot files against their sources, numerically.

  ur5.toml      against Universal Robots' published STANDARD DH table: the modified-DH chain of
                the robot file must give the same flange pose at random configurations.
  iiwa14.toml   against the joint origins of the IFL-CAMP iiwa_stack model
                (iiwa_description/urdf/iiwa14.xacro, link_0 .. link_7 plus the 0.045 m flange):
                same pose, so the joint directions and zero are KUKA's.
  puma560.toml  (a) against Corke's mdl_puma560akb.m (already modified DH): exact transcription;
                (b) the joint-convention map to Corke's standard-DH mdl_puma560.m that the file uses
                to carry that model's joint limits over: AKB(q) = Rz(pi) Std(q + (0,pi,pi,0,0,0))
                Rz(pi), exact in rotation and within the two models' millimetre-level length
                differences in position.

Uses PyKDL (Debian python3-pykdl): Frame.DH(a, alpha, d, theta) is standard DH
RotZ(theta) TransZ(d) TransX(a) RotX(alpha); Frame.DH_Craig1989(a, alpha, d, theta) is modified DH
RotX(alpha) TransX(a) RotZ(theta) TransZ(d). The robot files' chains come from fk_fixtures.py.

Run: python3 tools/verify_dh_conversions.py   (exits non-zero on a mismatch)
"""

import math
import os
import random
import sys

import PyKDL as kdl

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fk_fixtures as fk  # noqa: E402

PI = math.pi
N = 1000
EXACT = 1e-12


def robot(name):
    cfg = fk.load(os.path.join(fk.ROBOTS, f"{name}.toml"))
    chain = fk.build_chain(cfg)
    solver = kdl.ChainFkSolverPos_recursive(chain)
    return cfg, (chain, solver)  # keep the chain alive: the solver refers to it


def pose_error(f, g):
    dp = (f.p - g.p).Norm()
    dr = max(abs(f.M[i, j] - g.M[i, j]) for i in range(3) for j in range(3))
    return dp, dr


def random_configs(cfg, rng, n=N, span=None):
    for _ in range(n):
        if span is None:
            yield [rng.uniform(j["min"], j["max"]) for j in cfg["joints"]]
        else:
            yield [rng.uniform(-span, span) for _ in cfg["joints"]]


def standard_dh(rows, q):
    f = kdl.Frame.Identity()
    for (a, alpha, d, theta), v in zip(rows, q):
        f = f * kdl.Frame.DH(a, alpha, d, theta + v)
    return f


def modified_dh(rows, q):
    f = kdl.Frame.Identity()
    for (a, alpha, d, theta), v in zip(rows, q):
        f = f * kdl.Frame.DH_Craig1989(a, alpha, d, theta + v)
    return f


def report(label, dp, dr, tol_p, tol_r=EXACT):
    ok = dp <= tol_p and dr <= tol_r
    print(f"  [{'ok' if ok else 'FAIL'}] {label}: max position diff {dp:.2e} m (tol {tol_p:g}), "
          f"max rotation-entry diff {dr:.2e} (tol {tol_r:g})")
    return ok


def check_ur5(rng):
    print("UR5: robots/ur5.toml (modified DH) vs Universal Robots' standard DH")
    # (a, alpha, d, theta) per row, as published by Universal Robots for the UR5.
    ur5_std = [(0.0, PI / 2, 0.089159, 0.0),
               (-0.425, 0.0, 0.0, 0.0),
               (-0.39225, 0.0, 0.0, 0.0),
               (0.0, PI / 2, 0.10915, 0.0),
               (0.0, -PI / 2, 0.09465, 0.0),
               (0.0, 0.0, 0.0823, 0.0)]
    cfg, (_, solver) = robot("ur5")
    dp = dr = 0.0
    for q in random_configs(cfg, rng):
        e = pose_error(fk.fk_kdl(solver, q), standard_dh(ur5_std, q))
        dp, dr = max(dp, e[0]), max(dr, e[1])
    return report(f"{N} random configurations within the limits", dp, dr, EXACT)


def check_iiwa14(rng):
    print("iiwa14: robots/iiwa14.toml vs iiwa_stack iiwa14.xacro joint origins")
    # (xyz, rpy) of joint_1 .. joint_7, every axis local z; flange = link_7 + (0, 0, 0.045) with
    # rpy (pi, pi, pi) = identity rotation (joint "<robot>_joint_ee").
    origins = [((0.0, 0.0, 0.1575), (0.0, 0.0, 0.0)),
               ((0.0, 0.0, 0.2025), (PI / 2, 0.0, PI)),
               ((0.0, 0.2045, 0.0), (PI / 2, 0.0, PI)),
               ((0.0, 0.0, 0.2155), (PI / 2, 0.0, 0.0)),
               ((0.0, 0.1845, 0.0), (-PI / 2, PI, 0.0)),
               ((0.0, 0.0, 0.2155), (PI / 2, 0.0, 0.0)),
               ((0.0, 0.081, 0.0), (-PI / 2, PI, 0.0))]
    flange = kdl.Frame(kdl.Rotation.RPY(PI, PI, PI), kdl.Vector(0.0, 0.0, 0.045))

    def urdf(q):
        f = kdl.Frame.Identity()
        for (xyz, rpy), v in zip(origins, q):
            f = f * kdl.Frame(kdl.Rotation.RPY(*rpy), kdl.Vector(*xyz)) * kdl.Frame(
                kdl.Rotation.RotZ(v))
        return f * flange

    cfg, (_, solver) = robot("iiwa14")
    dp = dr = 0.0
    for q in random_configs(cfg, rng):
        e = pose_error(fk.fk_kdl(solver, q), urdf(q))
        dp, dr = max(dp, e[0]), max(dr, e[1])
    return report(f"{N} random configurations within the limits", dp, dr, EXACT)


def check_puma560(rng):
    print("puma560: robots/puma560.toml vs Corke mdl_puma560akb.m / mdl_puma560.m")
    # mdl_puma560akb.m, Link([theta d a alpha], 'modified') -> (a, alpha, d, theta)
    akb = [(0.0, 0.0, 0.0, 0.0),
           (0.0, -PI / 2, 0.2435, 0.0),
           (0.4318, 0.0, -0.0934, 0.0),
           (-0.0203, PI / 2, 0.4331, 0.0),
           (0.0, -PI / 2, 0.0, 0.0),
           (0.0, PI / 2, 0.0, 0.0)]
    # mdl_puma560.m (standard DH, Paul's twist signs) -> (a, alpha, d, theta)
    std = [(0.0, PI / 2, 0.0, 0.0),
           (0.4318, 0.0, 0.0, 0.0),
           (0.0203, -PI / 2, 0.15005, 0.0),
           (0.0, PI / 2, 0.4318, 0.0),
           (0.0, -PI / 2, 0.0, 0.0),
           (0.0, 0.0, 0.0, 0.0)]
    cfg, (_, solver) = robot("puma560")
    ok = True
    dp = dr = 0.0
    for q in random_configs(cfg, rng):
        e = pose_error(fk.fk_kdl(solver, q), modified_dh(akb, q))
        dp, dr = max(dp, e[0]), max(dr, e[1])
    ok &= report(f"(a) transcription of mdl_puma560akb, {N} configurations", dp, dr, EXACT)

    shift = [0.0, PI, PI, 0.0, 0.0, 0.0]
    rz = kdl.Frame(kdl.Rotation.RotZ(PI))
    dp = dr = 0.0
    for q in random_configs(cfg, rng, span=2 * PI):
        e = pose_error(modified_dh(akb, q),
                       rz * standard_dh(std, [v + s for v, s in zip(q, shift)]) * rz)
        dp, dr = max(dp, e[0]), max(dr, e[1])
    # Position differs only through d3 (-0.0934 + 0.2435 = 0.1501 vs 0.15005) and d4 (0.4331 vs
    # 0.4318): at most ~1.4 mm.
    ok &= report(f"(b) AKB(q) = Rz(pi) Std(q + (0,pi,pi,0,0,0)) Rz(pi), {N} configurations",
                 dp, dr, 2e-3)

    # Corke's limits (mdl_puma560.m qlim, degrees) mapped with q_akb = q_std - shift, then
    # wrapped by 2*pi into the representative that contains the AKB zero pose.
    std_deg = [(-160, 160), (-45, 225), (-225, 45), (-110, 170), (-100, 100), (-266, 266)]
    for i, ((lo, hi), s, joint) in enumerate(zip(std_deg, shift, cfg["joints"])):
        lo, hi = math.radians(lo) - s, math.radians(hi) - s
        while hi < 0.0:
            lo, hi = lo + 2 * PI, hi + 2 * PI
        while lo > 0.0:
            lo, hi = lo - 2 * PI, hi - 2 * PI
        good = abs(lo - joint["min"]) < 1e-12 and abs(hi - joint["max"]) < 1e-12
        ok &= good
        print(f"  [{'ok' if good else 'FAIL'}] joint {i + 1} limits: mapped "
              f"[{math.degrees(lo):.1f}, {math.degrees(hi):.1f}] deg, file "
              f"[{math.degrees(joint['min']):.1f}, {math.degrees(joint['max']):.1f}] deg")
    for label, q in [("qz", [0.0] * 6), ("qr", [0.0, -PI / 2, PI / 2, 0.0, 0.0, 0.0]),
                     ("qstretch", [0.0, 0.0, PI / 2, 0.0, 0.0, 0.0])]:
        inside = all(j["min"] <= v <= j["max"] for j, v in zip(cfg["joints"], q))
        ok &= inside
        print(f"  [{'ok' if inside else 'FAIL'}] AKB pose {label} lies within the limits")
    return ok


def main():
    rng = random.Random(fk.SEED)
    results = [check_ur5(rng), check_iiwa14(rng), check_puma560(rng)]
    if all(results):
        print("all conversions verified")
        return 0
    print("verification FAILED")
    return 1


if __name__ == "__main__":
    sys.exit(main())
