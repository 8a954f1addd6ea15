//! A chosen redundancy value over UDP (`KR`, docs/protocol.md): `armgate ik --theta3` lists
//! the solutions that keep it, `armgate ik-move --theta3` moves the arm to the pose with it.

use super::*;

use armgate_core::kinematics::Chain;
use armgate_core::math;

#[test]
fn ik_and_ik_move_take_a_chosen_theta3_on_a_seven_joint_arm() {
    let sim = Sim::start_with("iiwa14", &["--start", "0.1,0.5,0.3,-1.0,0.2,0.8,0.1"]);
    if !knows_status(&sim) {
        return;
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robots/iiwa14.toml");
    let chain = Chain::new(&armgate_core::config::load_file(&root).unwrap());
    // A pose whose configuration has another θ3 than the present joints.
    let target = [0.3, 0.7, -0.6, -1.2, 0.4, 0.6, -0.2];
    let pose = chain.forward(&target).unwrap();
    let t = pose.translation.vector;
    let [r, p, y] = math::rpy(&pose.rotation);
    let words: Vec<String> = [t.x, t.y, t.z, r, p, y]
        .iter()
        .map(|v| format!("{v:.9}"))
        .collect();
    let with = |head: &[&str]| -> Vec<String> {
        head.iter()
            .map(|s| (*s).to_owned())
            .chain(words.iter().cloned())
            .collect()
    };
    let run = |args: Vec<String>| {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        armgate(&sim, &args)
    };
    // Every solution listed keeps θ3 = −0.6.
    let (result, out) = run(with(&["ik", "--theta3", "-0.6"]));
    result.unwrap();
    let listed: Vec<&str> = out.lines().filter(|l| l.contains("branch ")).collect();
    assert!(listed.len() >= 2, "{out}");
    for line in &listed {
        // "branch N shoulder-…,elbow-…,wrist-… (lun) q1 q2 q3 …"
        let third = line.split_whitespace().nth(6).unwrap();
        assert_eq!(third, "-0.600000", "{out}");
    }
    // The controller refuses what the arm does not have, and values beyond the limits.
    assert_eq!(
        sim.text("KR", [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1),
        "ER26 Cmd KR j3 > 2.967"
    );
    assert!(
        sim.text("KR", [0.1, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0], 3)
            .starts_with("ER24 Cmd KR")
    );
    armgate(&sim, &["on"]).0.unwrap();
    armgate(&sim, &["mode", "joint"]).0.unwrap();
    let (result, out) = run(with(&[
        "ik-move",
        "--theta3",
        "-0.6",
        "--wait-timeout",
        "30s",
    ]));
    result.unwrap();
    assert!(out.contains("arrived"), "{out}");
    let low = sim.ok("jP", [0.0; 7], 0);
    let high = sim.ok("jP", [0.0; 7], 0x80);
    let q: Vec<f64> = low[..6]
        .iter()
        .chain(&high[..1])
        .map(|v| f64::from(*v))
        .collect();
    assert!((q[2] + 0.6).abs() < 1e-3, "{q:?}");
    let reached = chain.forward(&q).unwrap();
    assert!((reached.translation.vector - t).norm() < 1e-3, "{q:?}");
    // The choice was the command line's client's: another client's KG cannot ask for it.
    let values = [t.x, t.y, t.z, r, p, y, 0.0].map(|v| v as f32);
    assert!(sim.text("KG", values, 8 | 0x40).starts_with("ER24 Cmd KG"));
}

#[test]
fn ik_marks_the_present_branch_and_the_one_ik_move_takes() {
    // ranger-mk1 from the README's start; the README's ik pose has two solutions.
    let sim = Sim::start_with("ranger-mk1", &["--start", "1.5708,0.6,-0.4,0.2,1.8,0.1"]);
    if !knows_status(&sim) {
        return;
    }
    let pose = ["0", "0.2", "0.8", "0", "0", "-1.5708"];
    let (result, out) = armgate(&sim, &[&["ik"][..], &pose].concat());
    result.unwrap();
    let marked: Vec<&str> = out
        .lines()
        .filter(|l| l.contains("ik-move's choice"))
        .collect();
    assert_eq!(marked.len(), 1, "{out}");
    let chosen: u8 = marked[0]
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        out.lines().filter(|l| l.contains("present branch")).count() <= 1,
        "{out}"
    );
    eprintln!("{out}");
    let _ = sim.ok("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    wait_drives(&sim, 2.0);
    let (result, moved) = armgate(&sim, &[&["ik-move", "--no-wait"][..], &pose].concat());
    result.unwrap();
    assert!(
        moved.contains(&format!("(branch {chosen} ")),
        "ik marked {chosen}: {out}\nik-move: {moved}"
    );
    // The same branch by the names ik printed for it, once the first move is stopped.
    let _ = sim.ok("ST", [0.0; 7], 0);
    assert!(poll_status(&sim, Duration::from_secs(3), |s| s[4] == 0.0));
    let name = marked[0].split_whitespace().nth(2).unwrap();
    assert!(name.starts_with("shoulder-"), "{out}");
    let (result, again) = armgate(
        &sim,
        &[&["ik-move", "--no-wait", "--branch", name][..], &pose].concat(),
    );
    result.unwrap();
    assert!(
        again.contains(&format!("(branch {chosen} {name}")),
        "{again}"
    );
    let _ = sim.ok("ST", [0.0; 7], 0);
}

/// Issue 37 on the robots whose configurations came last: `armgate ik` names every solution
/// (on a 7–8 joint arm with the θ3 it keeps), marks the one `ik-move` takes, and `ik-move
/// --branch NAME` moves to each name it printed; hybrid has no wrist flag.
#[test]
fn ik_names_and_ik_move_takes_configurations_on_redundant_and_prismatic_arms() {
    for (name, start, keep) in [
        ("iiwa14", vec![0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1], vec![2]),
        // Its pretend joints start at home whatever --start says.
        ("hybrid", vec![0.0; 6], vec![]),
    ] {
        let start_arg: Vec<String> = start.iter().map(f64::to_string).collect();
        let sim = Sim::start_with(name, &["--start", &start_arg.join(",")]);
        if !knows_status(&sim) {
            return;
        }
        // The joints are the start's once the drives report them.
        wait_drives(&sim, 2.0);
        let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../robots/{name}.toml"));
        let chain = Chain::new(&armgate_core::config::load_file(&file).unwrap());
        let mut target: Vec<f64> = start.iter().map(|q| q + 0.1).collect();
        for &p in &keep {
            target[p] = start[p];
        }
        let pose = chain.forward(&target).unwrap();
        let t = pose.translation.vector;
        let [r, p, y] = math::rpy(&pose.rotation);
        let words: Vec<String> = [t.x, t.y, t.z, r, p, y]
            .iter()
            .map(|v| format!("{v:.9}"))
            .collect();
        let words: Vec<&str> = words.iter().map(String::as_str).collect();
        let (result, out) = armgate(&sim, &[&["ik"][..], &words].concat());
        result.unwrap();
        if keep.is_empty() {
            assert!(!out.contains("θ3"), "{name}: {out}");
        } else {
            assert!(out.contains("for θ3 = 0.300 (present)"), "{name}: {out}");
        }
        let listed: Vec<&str> = out.lines().filter(|l| l.contains("branch ")).collect();
        assert!(listed.len() >= 2, "{name}: {out}");
        if name == "hybrid" {
            assert!(!out.contains("wrist-flip"), "{out}");
        }
        let marked: Vec<&&str> = listed
            .iter()
            .filter(|l| l.contains("ik-move's choice"))
            .collect();
        assert_eq!(marked.len(), 1, "{name}: {out}");
        // The present configuration: the start's.
        let present = chain.configuration(&start).unwrap();
        assert_eq!(
            sim.ok("SQ", [0.0; 7], 5)[0],
            f32::from(present),
            "{name}: {out}"
        );
        let _ = sim.ok("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
        let chosen = marked[0].split_whitespace().nth(1).unwrap();
        let (result, moved) = armgate(&sim, &[&["ik-move", "--no-wait"][..], &words].concat());
        result.unwrap();
        assert!(
            moved.contains(&format!("(branch {chosen} ")),
            "{name}: {out}\n{moved}"
        );
        // Every name printed, by its short form, moves to that configuration, or is refused
        // because the way there runs one link into another (ER25 "L6 hits L4").
        let mut moved = 0;
        for line in &listed {
            let _ = sim.ok("ST", [0.0; 7], 0);
            assert!(poll_status(&sim, Duration::from_secs(3), |s| s[4] == 0.0));
            let number = line.split_whitespace().nth(1).unwrap();
            let short = line.split_whitespace().nth(3).unwrap();
            let short = short.trim_matches(['(', ')']);
            let (result, again) = armgate(
                &sim,
                &[&["ik-move", "--no-wait", "--branch", short][..], &words].concat(),
            );
            match result {
                Ok(()) => {
                    assert!(
                        again.contains(&format!("(branch {number} ")),
                        "{name} {short}: {again}"
                    );
                    moved += 1;
                }
                Err(e) => assert!(e.to_string().contains(" hits "), "{name} {short}: {e}"),
            }
        }
        assert!(moved >= 2, "{name}: {moved} of {out}");
        let _ = sim.ok("ST", [0.0; 7], 0);
    }
}
