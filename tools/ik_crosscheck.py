#!/usr/bin/env python3
"""Cross-checks armgate's closed-form IK against an independent all-solutions solver: EAIK
(PyPI `eaik`, C++ on IK-Geo's subproblems), which finds the decomposition itself from a URDF.

For each robot (default ranger-mk1, puma560, ur5):

1. `armgate urdf ROBOT.toml` (the `armgate-viz` binary) writes the URDF; EAIK's `UrdfRobot`
   reads it (axes and points at q = 0; its end effector is link_6's origin with the base's
   orientation at q = 0, so poses are carried between the two by the fixed transforms
   world->link_6 at q = 0 and link_6->tool, read from the same URDF with urchin). The map is
   checked first: EAIK's FK against armgate's at 200 configurations ("FK convention gap").
2. Joint vectors (numpy, seeded): N uniform in [-pi, pi)^6, and N/4 each of round angles
   (multiples of pi/2), a wrist 1e-9..1e-3 rad from q5 = 0 or pi, an elbow as near its
   stretched or folded value. armgate's FK gives the pose and `Chain::solve_all` every solution
   (core/examples/ik_solutions.rs with `--wide-limits`: every revolute joint limited to +-2pi,
   reference 0, so no limit drops a solution and each branch comes back once, within +-pi).
3. EAIK solves the same poses. Solutions are matched modulo 2pi (SAME = 1e-6 rad per joint);
   every solution of either side is checked by armgate's FK against the target (position m,
   rotation angle rad); "exact" means both errors <= 1e-9 (armgate's own check). A solution
   or original vector that armgate lacks is looked for again with it as the reference (a
   singular pose's free joint takes the reference's value); what is still missing is "near"
   (within NEAR = 1e-2 of armgate's nearest: the same root, moved by a near-singular pose's
   conditioning, where vectors that far apart all reproduce the pose within 1e-9) or
   "absent".
4. Timing (µs per all-solutions solve): armgate's solve_all (median of the uniform poses, one
   call each), EAIK's batched C++ call on one thread, and EAIK's and ik-geo's (PyPI `ik-geo`,
   IK-Geo's Rust implementation, family picked by hand) single calls from Python minus a
   Python call of the same library's FK (the call's own cost).

Needs numpy, eaik (and optionally ik-geo) from PyPI, cargo for the two binaries:
    python3 -m venv target/ik-crosscheck && target/ik-crosscheck/bin/pip install eaik ik-geo
    target/ik-crosscheck/bin/python tools/ik_crosscheck.py [--samples 2000] [--json out.json]
Not run in CI (it needs PyPI packages). Exits 1 if a solution EAIK finds exact, or an original
vector, is absent from armgate's solutions; 0 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
ROBOTS = ["ranger-mk1", "puma560", "ur5"]
EXACT = 1e-9
SAME = 1e-6
NEAR = 1e-2


def cargo_binaries() -> tuple[Path, Path]:
    """Builds (if needed) and returns the ik_solutions example and armgate-viz, release."""
    env = dict(os.environ, CARGO_INCREMENTAL="0")
    for args in (["-p", "armgate-core", "--example", "ik_solutions"], ["-p", "armgate-viz"]):
        subprocess.run(["cargo", "build", "-q", "--release", *args], cwd=REPO, env=env,
                       check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release"
    return target / "examples" / "ik_solutions", target / "armgate-viz"


def armgate(binary: Path, robot: Path, lines: list[str]) -> list[dict]:
    """Runs the ik_solutions example on `lines`; one parsed JSON object per line."""
    out = subprocess.run([str(binary), str(robot), "--wide-limits"], input="\n".join(lines),
                         capture_output=True, text=True, check=True).stdout
    return [json.loads(line) for line in out.splitlines()]


def line(mode: str, q) -> str:
    return mode + " " + " ".join(repr(float(v)) for v in q)


def errors(pose: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """Position (m) and rotation angle (rad) between two 4x4 frames."""
    r = target[:3, :3].T @ pose[:3, :3]
    s = 0.5 * np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    c = 0.5 * (np.trace(r) - 1.0)
    return float(np.linalg.norm(pose[:3, 3] - target[:3, 3])), float(np.arctan2(s, c))


def wrapped(a, b) -> float:
    d = np.asarray(a) - np.asarray(b)
    return float(np.max(np.abs(d - 2 * np.pi * np.round(d / (2 * np.pi)))))


class EaikModel:
    """EAIK's robot from the URDF, and the map between armgate's tool poses and its poses."""

    def __init__(self, urdf: Path):
        from eaik.IK_URDF import UrdfRobot
        from urchin import URDF

        self.robot = UrdfRobot(str(urdf))
        self.urdf = model = URDF.load(str(urdf), lazy_load_meshes=True)
        zero = model.link_fk()
        frames = {link.name: zero[link] for link in model.links}
        last = f"link_{len(model.actuated_joints)}"
        # tool = link_n(q) * to_tool; EAIK's pose = link_n(q) * link_n(0)^-1 rotation part.
        self.to_tool = np.linalg.inv(frames[last]) @ frames["tool"]
        self.last_zero = frames[last][:3, :3]

    def pose_of(self, tool: np.ndarray) -> np.ndarray:
        link = tool @ np.linalg.inv(self.to_tool)
        pose = link.copy()
        pose[:3, :3] = link[:3, :3] @ self.last_zero.T
        return pose

    def stretched_elbow(self) -> float:
        """q3 where link_4's origin (on axis 4; the wrist centre of a spherical wrist) is
        farthest from axis 2: that distance squared is A + B cos(q3 - phi), so three values
        give phi."""
        def distance2(q3: float) -> float:
            frames = self.urdf.link_fk(cfg={"joint_3": q3})
            f2, f4 = frames[self.urdf.link_map["link_2"]], frames[self.urdf.link_map["link_4"]]
            v = f4[:3, 3] - f2[:3, 3]
            return float(v @ v - (v @ f2[:3, 2]) ** 2)

        f0, f1, f2 = (distance2(x) for x in (0.0, np.pi / 2, np.pi))
        return float(np.arctan2(f1 - 0.5 * (f0 + f2), 0.5 * (f0 - f2)))

    def solve(self, tool: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s = self.robot.IK(self.pose_of(tool))
        q = np.asarray(s.Q).reshape(-1, 6) if s.num_solutions() else np.zeros((0, 6))
        return q, np.asarray(s.is_LS, dtype=bool).reshape(-1)


def samples_of(model: EaikModel, count: int, rng: np.random.Generator) -> dict:
    """The joint vectors of each set: uniform in [-pi, pi)^6; round (every joint a multiple of
    pi/2: singular poses with free joints); the wrist within 1e-9..1e-3 rad of q5 = 0 or pi (axes
    4 and 6 in line, or nearly: ranger-mk1's rounded twists 1.5708 keep them 7e-6 apart); the
    elbow as near its stretched or folded value (where the wrist centre's distance from axis 2
    is extreme)."""
    uniform = rng.uniform(-np.pi, np.pi, size=(count, 6))
    round_ = rng.integers(-2, 2, size=(count // 4, 6)) * (np.pi / 2)
    near = count // 4

    def offset() -> np.ndarray:
        return rng.choice([-1.0, 1.0], near) * 10.0 ** rng.uniform(-9, -3, near)

    wrist = rng.uniform(-np.pi, np.pi, size=(near, 6))
    wrist[:, 4] = rng.choice([0.0, np.pi], near) + offset()
    elbow = rng.uniform(-np.pi, np.pi, size=(near, 6))
    elbow[:, 2] = model.stretched_elbow() + rng.choice([0.0, np.pi], near) + offset()
    wrap = lambda q: (q + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
    return dict(uniform=uniform, round=round_, wrist=wrap(wrist), elbow=wrap(elbow))


def compare(example: Path, robot: Path, model: EaikModel, qs: np.ndarray) -> dict:
    """One set of joint vectors: armgate's and EAIK's solutions of their poses, compared."""
    ours = armgate(example, robot, [line("ik", q) for q in qs])
    targets = [np.array(o["pose"]).reshape(4, 4) for o in ours]
    theirs = [model.solve(t) for t in targets]
    # armgate's FK of every solution of both sides, in one run of the example.
    listed = [(k, "eaik", j, q) for k, (sol, _) in enumerate(theirs) for j, q in enumerate(sol)]
    listed += [(k, "armgate", j, s["q"]) for k, o in enumerate(ours)
               for j, s in enumerate(o["solutions"])]
    poses = armgate(example, robot, [line("fk", q) for (_, _, _, q) in listed])
    fk = {(k, side, j): errors(np.array(p["pose"]).reshape(4, 4), targets[k])
          for (k, side, j, _), p in zip(listed, poses)}

    r = dict(poses=len(qs), ours=0, theirs=0, theirs_ls=0, theirs_exact=0, ours_error=0.0,
             theirs_inexact_poses=0,
             theirs_exact_error=0.0, theirs_error=0.0, original_missing=[],
             missing_in_ours=[], missing_in_theirs=[], representatives=0, fewer_theirs=0,
             ours_us=float(np.median([o["micros"] for o in ours])))
    for k, (o, (sol, ls)) in enumerate(zip(ours, theirs)):
        mine = [s["q"] for s in o["solutions"]]
        r["ours"] += len(mine)
        r["theirs"] += len(sol)
        r["theirs_ls"] += int(ls.sum())
        r["theirs_inexact_poses"] += any(max(fk[(k, "eaik", j)]) > EXACT for j in range(len(sol)))
        for j in range(len(mine)):
            r["ours_error"] = max(r["ours_error"], *fk[(k, "armgate", j)])
        if not any(wrapped(m, qs[k]) < SAME for m in mine):
            r["original_missing"].append(k)
        exact_theirs = 0
        for j, q in enumerate(sol):
            e = fk[(k, "eaik", j)]
            r["theirs_error"] = max(r["theirs_error"], *e)
            if max(e) > EXACT:
                continue
            exact_theirs += 1
            r["theirs_exact"] += 1
            r["theirs_exact_error"] = max(r["theirs_exact_error"], *e)
            if not any(wrapped(m, q) < SAME for m in mine):
                r["missing_in_ours"].append(dict(k=k, q=qs[k].tolist(), eaik=q.tolist(),
                                                 fk_error=e, ls=bool(ls[j]), armgate=mine))
        r["fewer_theirs"] += exact_theirs < len(mine)
        for j, m in enumerate(mine):
            near = min([wrapped(m, q) for q in sol], default=np.inf)
            if near >= SAME:
                r["missing_in_theirs"].append(dict(k=k, q=qs[k].tolist(), armgate=m, nearest=near,
                                                   fk_error=fk[(k, "armgate", j)],
                                                   eaik=sol.tolist()))
    # A singular pose has a continuum of solutions: armgate gives a joint that it leaves free
    # the reference's value. So each missing solution (and a missing original vector) is
    # looked for again among armgate's solutions with it as the reference; what is still
    # missing is binned by its distance from armgate's nearest solution: within NEAR it is
    # the same root, split or moved by a near-singular pose's conditioning (where joint
    # vectors that far apart reproduce the pose within EXACT).
    wanted = [(c["k"], np.array(c["eaik"])) for c in r["missing_in_ours"]]
    wanted += [(k, qs[k]) for k in r["original_missing"]]
    answers = armgate(example, robot, [line("ik", [*qs[k], *w]) for k, w in wanted])
    nearest = [min([wrapped(m["q"], w) for m in [*ours[k]["solutions"], *a["solutions"]]],
                   default=np.inf) for (k, w), a in zip(wanted, answers)]
    split = len(r["missing_in_ours"])
    for c, d in zip(r["missing_in_ours"], nearest[:split]):
        c["nearest"] = d
    r["representatives"] = sum(d < SAME for d in nearest[:split])
    r["missing_in_ours"] = [c for c in r["missing_in_ours"] if c["nearest"] >= SAME]
    r["original_missing"] = [dict(q=qs[k].tolist(), nearest=d)
                             for k, d in zip(r["original_missing"], nearest[split:]) if d >= SAME]
    return r


def robot_results(name: str, count: int, seed: int, binaries: tuple[Path, Path],
                  workdir: Path) -> dict:
    example, viz = binaries
    robot = REPO / "robots" / f"{name}.toml"
    urdf = workdir / f"{name}.urdf"
    subprocess.run([str(viz), "urdf", str(robot), "--out", str(urdf)], check=True)
    model = EaikModel(urdf)
    sets = samples_of(model, count, np.random.default_rng(seed))
    uniform = sets["uniform"]
    targets = [np.array(o["pose"]).reshape(4, 4)
               for o in armgate(example, robot, [line("fk", q) for q in uniform[:200]])]
    # The two FK conventions agree (the pose map is right) before anything is compared.
    fk_gap = max(max(errors(np.asarray(model.robot.fwdKin(q)), model.pose_of(t)))
                 for q, t in zip(uniform, targets))
    results = {kind: compare(example, robot, model, qs) for kind, qs in sets.items()}
    times = timing(model, [model.pose_of(t) for t in targets], name)
    times["armgate"] = results["uniform"]["ours_us"]
    return dict(robot=name, eaik_family=model.robot.getKinematicFamily(), fk_gap=fk_gap,
                sets=results, timing=times)


def median_us(call, items: list, repeats: int = 5) -> float:
    """Median over `repeats` runs of the time per item of `call(item)`, in microseconds."""
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for item in items:
            call(item)
        runs.append((time.perf_counter() - t0) / len(items) * 1e6)
    return float(np.median(runs))


def timing(model: EaikModel, poses: list[np.ndarray], name: str) -> dict:
    """Time per all-solutions solve (µs): EAIK's batched C++ call on one thread over 20,000
    poses (one call; Python converts the poses and the answers), EAIK's and ik-geo's single
    calls from Python, and the cost of a Python call of each library's FK with the same
    arguments (what a single call's figure carries besides the solve)."""
    batch = [poses[k % len(poses)] for k in range(20_000)]
    out = dict(eaik_batched=median_us(lambda b: model.robot.IK_batched(b, 1), [batch]) / len(batch))
    out["eaik_single"] = median_us(model.robot.IK, poses)
    q = np.zeros(6)
    out["eaik_fk_call"] = median_us(lambda p: model.robot.fwdKin(q), poses)
    geo = ik_geo_robot(model, name)
    if geo is not None:
        pairs = [(p[:3, :3].copy(), p[:3, 3].copy()) for p in poses]
        out["ik_geo_single"] = median_us(lambda rt: geo.get_ik(*rt), pairs)
        out["ik_geo_fk_call"] = median_us(lambda rt: geo.forward_kinematics(q), pairs)
    return out


def ik_geo_robot(model: EaikModel, name: str):
    """IK-Geo's Rust solver (PyPI `ik-geo`) for the same axes, its family picked by hand (it
    does not detect one); None if not installed."""
    try:
        import ik_geo
    except ImportError:
        return None
    h = np.asarray(model.robot.getOriginal_H()).reshape(3, -1).T
    p = np.asarray(model.robot.getOriginal_P()).reshape(3, -1).T
    if name == "ur5":
        return ik_geo.Robot.three_parallel_two_intersecting(h.tolist(), p.tolist())
    return ik_geo.Robot.spherical_two_parallel(h.tolist(), p.tolist())


def report(results: list[dict]) -> None:
    print(row(["robot", "set", "poses", "solutions armgate / EAIK (mean)",
               "EAIK least-squares / exact (mean)", "poses with an inexact EAIK solution",
               "exact EAIK solutions armgate lacks: near / absent (found with it as the "
               "reference: a free joint's value)",
               "armgate solutions EAIK lacks: near / absent (poses where EAIK has fewer exact)",
               "original q missing in armgate: near / absent",
               "max FK error armgate / EAIK exact / EAIK any"]))
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        for kind, s in r["sets"].items():
            n = s["poses"]
            print(f"| {r['robot']} | {kind} | {n} | {s['ours'] / n:.3f} / {s['theirs'] / n:.3f} | "
                  f"{s['theirs_ls'] / n:.3f} / {s['theirs_exact'] / n:.3f} | "
                  f"{100 * s['theirs_inexact_poses'] / n:.1f} % | "
                  f"{bins(s['missing_in_ours'])} ({s['representatives']}) | "
                  f"{bins(s['missing_in_theirs'])} ({s['fewer_theirs']}) | "
                  f"{bins(s['original_missing'])} | {s['ours_error']:.1e} / "
                  f"{s['theirs_exact_error']:.1e} / {s['theirs_error']:.1e} |")
    print()
    print(row(["robot", "EAIK family", "FK convention gap",
               "armgate solve_all, ±2π limits (median)", "EAIK batched, 1 thread",
               "EAIK single call − its FK call", "ik-geo single call − its FK call"]))
    print("|---|---|---|---|---|---|---|")
    for r in results:
        t = r["timing"]

        def net(call: str, fk: str) -> str:
            return f"{t[call]:.2f} − {t[fk]:.2f} = {t[call] - t[fk]:.2f}" if call in t else "-"

        print(f"| {r['robot']} | {r['eaik_family']} | {r['fk_gap']:.1e} | {t['armgate']:.2f} | "
              f"{t['eaik_batched']:.2f} | {net('eaik_single', 'eaik_fk_call')} | "
              f"{net('ik_geo_single', 'ik_geo_fk_call')} |")
    for r in results:
        for kind, s in r["sets"].items():
            absent = lambda cases: [c for c in cases if c["nearest"] >= NEAR]  # noqa: E731
            for case in absent(s["missing_in_ours"])[:3]:
                print(f"{r['robot']} {kind}: EAIK's exact solution not in armgate's: {case}")
            for case in absent(s["original_missing"])[:3]:
                print(f"{r['robot']} {kind}: armgate lacks the original vector {case}")
            for case in absent(s["missing_in_theirs"])[:3]:
                print(f"{r['robot']} {kind}: armgate's solution not in EAIK's: {case}")


def row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def bins(cases: list[dict]) -> str:
    """How many cases lie within NEAR of the other side's nearest solution / farther."""
    near = sum(c["nearest"] < NEAR for c in cases)
    return f"{near} / {len(cases) - near}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=2000,
                        help="uniform joint vectors per robot (a quarter as many per other set)")
    parser.add_argument("--seed", type=int, default=26)
    parser.add_argument("--robots", nargs="+", default=ROBOTS)
    parser.add_argument("--json", type=Path, help="write every result (and case) here")
    args = parser.parse_args()
    binaries = cargo_binaries()
    with tempfile.TemporaryDirectory() as tmp:
        results = [robot_results(name, args.samples, args.seed, binaries, Path(tmp))
                   for name in args.robots]
    print(f"EAIK {version('eaik')}, ik-geo {version('ik-geo')}, {args.samples} uniform poses "
          f"per robot, seed {args.seed}; times in µs")
    report(results)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return int(any(c["nearest"] >= NEAR for r in results for s in r["sets"].values()
                   for c in [*s["missing_in_ours"], *s["original_missing"]]))


def version(package: str) -> str:
    from importlib.metadata import PackageNotFoundError, version as installed

    try:
        return installed(package)
    except PackageNotFoundError:
        return "not installed"


if __name__ == "__main__":
    sys.exit(main())
