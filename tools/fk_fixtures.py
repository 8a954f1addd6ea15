#!/usr/bin/python3
"""Independent forward-kinematics reference fixtures for every robot file.

For each robots/*.toml this builds an Orocos KDL chain (PyKDL, Debian package python3-pykdl) and
writes core/tests/fixtures/fk_<robot-name>.csv with the tool pose at:

  row 1      all joints 0
  row 2      the midpoint of the joint limits
  row 3      the drives' `home` vector
  rows 4-23  20 configurations drawn uniformly within the limits (fixed seed, per robot)
  rows 24-   reference configurations quoted in the seed spec, for the robots that have them

Columns: q1..qn, x, y, z, r00, r01, r02, r10, r11, r12, r20, r21, r22 (rotation row-major),
metres and radians, every value printed with repr() (shortest string that round-trips an IEEE
double, i.e. at most 17 significant digits).

The chain (modified DH, Craig 1989, spec section 3.1/3.3):

  T_0T(q) = prod_i [RotX(alpha_i) TransX(a_i) RotZ(theta_i) TransZ(d_i)] * Tool
  revolute i:  theta_i = theta + q_i      prismatic i:  d_i = d + q_i
  Tool = DH_Craig1989(a, alpha, d, theta) * Trans(xyz) * RPY(rpy)

RotZ(q)/TransZ(q) commute with the row's own RotZ(theta)TransZ(d), so row i equals
DH_Craig1989(a_i, alpha_i, d_i, theta_i) * Joint_i(q_i) with the constants alone in the frame.
The KDL chain is therefore: a fixed segment carrying row 1's constant frame, then for k = 1..n a
segment whose joint is joint k (RotZ or TransZ about the local z) and whose tip frame is row k+1's
constant frame (the tool frame for k = n). Every pose is cross-checked against a direct product of
per-row DH_Craig1989 frames (variable added to the row's own theta or d) and against a plain-Python
4x4 implementation of the spec's matrix; any disagreement above 1e-12 aborts.

Sanity checks against values quoted in the seed spec are printed; a failure exits non-zero.

Regenerate with:  python3 tools/fk_fixtures.py   (a python3 that has PyKDL; /usr/bin/python3 on
Debian with python3-pykdl installed). Writing is deterministic: same input, same bytes.
"""

import glob
import math
import os
import random
import sys
import tomllib

import PyKDL as kdl

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROBOTS = os.path.join(ROOT, "robots")
FIXTURES = os.path.join(ROOT, "core", "tests", "fixtures")
SEED = 20100
N_RANDOM = 20
CROSS_TOL = 1e-12

# Reference configurations quoted in the seed spec (appended to that robot's CSV).
GOLDEN_Q = [-1.5838, 2.0360, 1.3499, -0.2471, 1.2428, -0.0595]  # spec 2.4, Fig. 3.3
HYBRID_Q = [0.3, 0.1, 0.2, 0.5, -0.5, 0.1]  # spec 3.6, Table 4.6
MK2_Q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]  # spec 3.6, Table 4.7
EXTRA_ROWS = {
    "ranger-mk1": [GOLDEN_Q],
    "ranger-mk1-jerk": [GOLDEN_Q],  # ranger-mk1 with jerk-limited profiles: same geometry
    "hybrid": [HYBRID_Q],
    "ranger-mk2": [MK2_Q],
}


def load(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


def tool_frame(cfg):
    t = cfg.get("tool", {})
    xyz = t.get("xyz", [0.0, 0.0, 0.0])
    rpy = t.get("rpy", [0.0, 0.0, 0.0])
    dh = kdl.Frame.DH_Craig1989(t.get("a", 0.0), t.get("alpha", 0.0), t.get("d", 0.0),
                                t.get("theta", 0.0))
    return dh * kdl.Frame(kdl.Rotation.RPY(*rpy), kdl.Vector(*xyz))


def is_prismatic(joint):
    kind = joint["type"]
    if kind not in ("revolute", "prismatic"):
        raise ValueError(f"unknown joint type {kind!r}")
    return kind == "prismatic"


def const_frame(joint):
    """Row i with the joint variable at 0: DH_Craig1989(a, alpha, d, theta)."""
    return kdl.Frame.DH_Craig1989(joint["a"], joint["alpha"], joint["d"], joint["theta"])


def build_chain(cfg):
    joints = cfg["joints"]
    chain = kdl.Chain()
    chain.addSegment(kdl.Segment("base", kdl.Joint("fixed", kdl.Joint.Fixed),
                                 const_frame(joints[0])))
    for k, joint in enumerate(joints):
        kind = kdl.Joint.TransZ if is_prismatic(joint) else kdl.Joint.RotZ
        tip = const_frame(joints[k + 1]) if k + 1 < len(joints) else tool_frame(cfg)
        chain.addSegment(kdl.Segment(f"link{k + 1}", kdl.Joint(f"q{k + 1}", kind), tip))
    return chain


def fk_kdl(solver, q):
    arr = kdl.JntArray(len(q))
    for i, v in enumerate(q):
        arr[i] = v
    out = kdl.Frame()
    if solver.JntToCart(arr, out) < 0:
        raise RuntimeError("ChainFkSolverPos_recursive failed")
    return out


def dh_row(joint, v):
    """The row's (a, alpha, d, theta) with the joint variable `v` in its own slot."""
    a, alpha, d, theta = joint["a"], joint["alpha"], joint["d"], joint["theta"]
    if is_prismatic(joint):
        d += v
    else:
        theta += v
    return a, alpha, d, theta


def fk_rows(cfg, q):
    """Direct product of per-row DH_Craig1989 frames, variable in the row's own slot."""
    f = kdl.Frame.Identity()
    for joint, v in zip(cfg["joints"], q):
        f = f * kdl.Frame.DH_Craig1989(*dh_row(joint, v))
    return f * tool_frame(cfg)


def matmul(x, y):
    return [[sum(x[i][k] * y[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def craig(a, alpha, d, theta):
    """The spec's section 3.1 matrix, written out."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return [[ct, -st, 0.0, a],
            [st * ca, ct * ca, -sa, -sa * d],
            [st * sa, ct * sa, ca, ca * d],
            [0.0, 0.0, 0.0, 1.0]]


def fk_plain(cfg, q):
    """Pure-Python 4x4 product, independent of KDL (tool RPY = Rz(yaw) Ry(pitch) Rx(roll))."""
    m = [[float(i == j) for j in range(4)] for i in range(4)]
    for joint, v in zip(cfg["joints"], q):
        m = matmul(m, craig(*dh_row(joint, v)))
    t = cfg.get("tool", {})
    m = matmul(m, craig(t.get("a", 0.0), t.get("alpha", 0.0), t.get("d", 0.0),
                        t.get("theta", 0.0)))
    roll, pitch, yaw = t.get("rpy", [0.0, 0.0, 0.0])
    x, y, z = t.get("xyz", [0.0, 0.0, 0.0])
    ca, sa = math.cos(yaw), math.sin(yaw)
    cb, sb = math.cos(pitch), math.sin(pitch)
    cc, sc = math.cos(roll), math.sin(roll)
    extra = [[ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc, x],
             [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc, y],
             [-sb, cb * sc, cb * cc, z],
             [0.0, 0.0, 0.0, 1.0]]
    return matmul(m, extra)


def frame_values(f):
    return [f.p[0], f.p[1], f.p[2]] + [f.M[i, j] for i in range(3) for j in range(3)]


def matrix_values(m):
    return [m[0][3], m[1][3], m[2][3]] + [m[i][j] for i in range(3) for j in range(3)]


def max_diff(u, v):
    return max(abs(x - y) for x, y in zip(u, v))


def configurations(cfg):
    joints = cfg["joints"]
    n = len(joints)
    rows = [[0.0] * n,
            [0.5 * (j["min"] + j["max"]) for j in joints],
            [float(j["drive"]["home"]) for j in joints]]
    rng = random.Random(SEED)
    for _ in range(N_RANDOM):
        rows.append([rng.uniform(j["min"], j["max"]) for j in joints])
    for q in EXTRA_ROWS.get(cfg["name"], []):
        if len(q) != n:
            raise ValueError(f"{cfg['name']}: reference configuration has {len(q)} joints")
        rows.append(list(q))
    return rows


def write_fixture(cfg, solver):
    n = len(cfg["joints"])
    header = [f"q{i + 1}" for i in range(n)] + ["x", "y", "z"] + [
        f"r{i}{j}" for i in range(3) for j in range(3)]
    lines = [",".join(header)]
    worst = 0.0
    for q in configurations(cfg):
        f = fk_kdl(solver, q)
        values = frame_values(f)
        worst = max(worst, max_diff(values, frame_values(fk_rows(cfg, q))),
                    max_diff(values, matrix_values(fk_plain(cfg, q))))
        lines.append(",".join(repr(float(v)) for v in list(q) + values))
    if worst > CROSS_TOL:
        raise SystemExit(f"{cfg['name']}: KDL chain and direct DH product disagree by {worst:g}")
    path = os.path.join(FIXTURES, f"fk_{cfg['name']}.csv")
    with open(path, "w", newline="\n") as out:
        out.write("\n".join(lines) + "\n")
    return path, len(lines) - 1, worst


def quaternion_xyzw(f):
    return list(f.M.GetQuaternion())  # KDL returns (x, y, z, w)


class Checks:
    def __init__(self):
        self.failed = 0

    def vec(self, label, got, want, tol):
        err = max(abs(g - w) for g, w in zip(got, want))
        ok = err <= tol
        self.failed += not ok
        fmt = ", ".join(f"{v:+.6f}" for v in got)
        ref = ", ".join(f"{v:+.6f}" for v in want)
        print(f"  [{'ok' if ok else 'FAIL'}] {label}: ({fmt}) vs ({ref}), "
              f"max err {err:.2e} (tol {tol:g})")

    def quat(self, label, got, want, tol):
        # q and -q are the same rotation
        if sum(g * w for g, w in zip(got, want)) < 0:
            got = [-g for g in got]
        self.vec(label, got, want, tol)


def sanity(chains):
    print("Sanity checks against the seed spec:")
    c = Checks()

    def pose(name, q):
        return fk_kdl(chains[name][1], q)

    if "ranger-mk1" in chains:
        f = pose("ranger-mk1", GOLDEN_Q)
        c.vec("ranger-mk1 golden vector position (spec 2.4)", list(f.p), [-0.0543, 0.5242, 0.2138],
              2e-4)
        c.vec("ranger-mk1 golden vector RPY", list(f.M.GetRPY()), [-0.0007, 1.4801, 1.7917], 2e-4)
        c.quat("ranger-mk1 golden vector quaternion (x,y,z,w)", quaternion_xyzw(f),
               [-0.5266, 0.4212, 0.5767, 0.4612], 2e-4)
        f = pose("ranger-mk1", [1.5708, 0.0, 1.5708, 0.0, 1.5708, 0.0])
        c.vec("ranger-mk1 home position (spec 3.6)", list(f.p), [0.0, 0.0200, 0.6660], 1e-4)
        c.quat("ranger-mk1 home quaternion", quaternion_xyzw(f), [0.0, 0.0, -0.70711, 0.70711],
               1e-4)
    if "hybrid" in chains:
        c.vec("hybrid q = 0 position (spec 3.6)", list(pose("hybrid", [0.0] * 6).p),
              [0.0, -0.5, -0.5], 1e-12)
        c.vec("hybrid q = (0.3, 0.1, 0.2, 0.5, -0.5, 0.1) position", list(pose("hybrid",
                                                                              HYBRID_Q).p),
              [0.18717, -0.73005, -0.26029], 1e-5)
    if "ranger-mk2" in chains:
        f = pose("ranger-mk2", [0.0] * 8)
        c.vec("ranger-mk2 q = 0 position (spec 3.6)", list(f.p), [0.1524, -0.070711, 1.273711],
              1e-6)
        c.quat("ranger-mk2 q = 0 quaternion", quaternion_xyzw(f),
               [0.382683, 0.0, 0.0, 0.923880], 1e-6)
        f = pose("ranger-mk2", MK2_Q)
        c.vec("ranger-mk2 q = (0.1 .. 0.8) position", list(f.p), [-0.249378, -0.139809, 1.213895],
              1e-6)
        c.quat("ranger-mk2 q = (0.1 .. 0.8) quaternion", quaternion_xyzw(f),
               [0.285809, -0.544166, 0.747137, 0.252947], 1e-6)
    if "ranger-mk1-table21" in chains:
        # Table 2.1 differs from the deployed set by millimetres: the golden vector should move
        # by that order only.
        f = pose("ranger-mk1-table21", GOLDEN_Q)
        c.vec("ranger-mk1-table21 golden joints (near the deployed pose)", list(f.p),
              [-0.0543, 0.5242, 0.2138], 1e-2)
    return c.failed


def main():
    os.makedirs(FIXTURES, exist_ok=True)
    chains = {}
    for path in sorted(glob.glob(os.path.join(ROBOTS, "*.toml"))):
        cfg = load(path)
        chain = build_chain(cfg)
        if chain.getNrOfJoints() != len(cfg["joints"]):
            raise SystemExit(f"{path}: chain has {chain.getNrOfJoints()} joints")
        solver = kdl.ChainFkSolverPos_recursive(chain)
        out, rows, worst = write_fixture(cfg, solver)
        # The solver keeps a C++ reference to the chain: keep the Python object alive with it.
        chains[cfg["name"]] = (cfg, solver, chain)
        print(f"{os.path.relpath(out, ROOT)}: {rows} rows, {len(cfg['joints'])} joints, "
              f"KDL chain vs direct DH product max diff {worst:.1e}")
    failed = sanity(chains)
    if failed:
        print(f"{failed} sanity check(s) FAILED")
        return 1
    print("all sanity checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
