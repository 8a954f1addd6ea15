//! The files calibration reads and writes, and the pose planner's guarantees.
#![allow(clippy::unwrap_used, clippy::panic)] // helpers of tests: a panic is a failed test

use armgate_calibrate::identify;
use armgate_calibrate::measurements::{format, format_poses, parse, parse_poses};
use armgate_calibrate::model::{FitSet, Geometry, MeasuredIn, Param};
use armgate_calibrate::robot_file::{BEGIN, END, edit};
use armgate_calibrate::{plan, sim};
use armgate_core::config::{ValidRobot, parse_toml};
use armgate_core::kinematics::Chain;
use armgate_core::motion::Workspace;

fn text(name: &str) -> String {
    std::fs::read_to_string(format!(
        "{}/../robots/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn robot(name: &str) -> ValidRobot {
    parse_toml(&text(name)).unwrap()
}

#[test]
fn the_written_file_changes_only_the_fitted_values() {
    let original = text("ranger-mk1");
    let nominal = robot("ranger-mk1");
    let truth = sim::perturb(&nominal, &sim::Errors::TYPICAL, 9).unwrap();
    let fitted = Geometry::new(&nominal).constants(FitSet::All);
    let written = edit(
        &original,
        &Geometry::new(&truth),
        &fitted,
        None,
        "line one\n\nline two",
    )
    .unwrap();

    // It loads, and is the truth (to the written resolution) in every respect.
    let reloaded = parse_toml(&written).unwrap();
    let (a, b) = (Chain::new(&reloaded), Chain::new(&truth));
    for q in plan::random_poses(&nominal, 10, 2).unwrap() {
        let (p, t) = (a.forward(&q).unwrap(), b.forward(&q).unwrap());
        let (p, t) = (p.translation.vector, t.translation.vector);
        assert!((p.x - t.x).abs() + (p.y - t.y).abs() + (p.z - t.z).abs() < 1e-8);
    }
    let mut expected = truth.clone().into_config();
    expected.joints = reloaded.joints.clone();
    expected.base = reloaded.base;
    expected.tool = reloaded.tool;
    assert_eq!(*reloaded, expected);

    // The comment block comes first; every original comment line survives.
    assert!(written.starts_with(&format!("{BEGIN}\n# line one\n#\n# line two\n{END}\n")));
    for line in original.lines().filter(|l| l.trim_start().starts_with('#')) {
        assert!(written.contains(line), "lost: {line}");
    }
    // Line by line, only fitted keys differ: the rest (limits, drives, …) keeps its text.
    let body = written.split_once(&format!("{END}\n")).unwrap().1;
    let fitted_key = |line: &str| {
        let key = line.split('=').next().unwrap_or("").trim();
        [
            "theta", "d", "a", "alpha", "beta", "xyz", "rpy", "[base]", "",
        ]
        .contains(&key)
    };
    let (old, new): (Vec<&str>, Vec<&str>) = (original.lines().collect(), body.lines().collect());
    for line in new.iter().filter(|l| !old.contains(l)) {
        assert!(fitted_key(line), "added or changed: {line}");
    }
    for line in old.iter().filter(|l| !new.contains(l)) {
        assert!(fitted_key(line), "removed or changed: {line}");
    }
}

#[test]
fn calibrating_again_replaces_the_comment_block() {
    let nominal = robot("ur5");
    let g = Geometry::new(&nominal);
    let once = edit(&text("ur5"), &g, &[Param::Theta(0)], None, "first").unwrap();
    let twice = edit(&once, &g, &[Param::Theta(0)], None, "second").unwrap();
    assert_eq!(twice.matches(BEGIN).count(), 1);
    assert!(twice.contains("# second") && !twice.contains("# first"));
    assert_eq!(twice.replace("# second", "# first"), once);
}

#[test]
fn measurements_round_trip() {
    let nominal = robot("ur5");
    let poses = plan::random_poses(&nominal, 4, 1).unwrap();
    let measured = sim::measure(&nominal, &poses, 1e-4, 1);
    let text = format(&measured, 6);
    let back = parse(&text, 6).unwrap();
    for (a, b) in measured.iter().zip(&back) {
        assert!((a.position - b.position).norm() < 1e-11);
        assert_eq!(a.weight, b.weight);
    }
    assert_eq!(parse_poses(&format_poses(&poses, 6), 6).unwrap().len(), 4);
    // Comments, a header, blank lines, an optional weight; errors name the line.
    let text = "# a comment\nq1,q2,x,y,z,w\n\n0,1,2,3,4,1\n0,1,2,3,4,0.5\n";
    let two = parse(text, 2).unwrap();
    assert_eq!((two[0].weight, two[1].weight), (1.0, 0.5));
    assert_eq!((two[0].line, two[1].line), (4, 5));
    // A plan's header names only the joints; x, y, z appended to each line.
    assert_eq!(parse("q1,q2\n0,1,2,3,4\n0,1,2,3,4\n", 2).unwrap().len(), 2);
    assert_eq!(parse("0,1,2,3\n", 2).unwrap_err().line, 1);
    // A missing z with the weight kept is not read as z = weight: the line is named.
    let missing = "0,1,2,3,4,1\n0,1,2,3,1\n0,1,2,3,4,1\n";
    let err = parse(missing, 2).unwrap_err();
    assert_eq!(err.line, 2, "{err}");
    assert!(err.reason.contains("missing"), "{err}");
    let err = parse("q1,q2,x,y,z,weight\n0,1,2,3,1\n", 2).unwrap_err();
    assert_eq!(err.line, 2, "{err}");
    assert_eq!(parse("0,1,2,3,4\n0,x,2,3,4\n", 2).unwrap_err().line, 2);
    assert_eq!(parse("0,1,2,3,4,-1\n", 2).unwrap_err().line, 1);
}

#[test]
fn planned_poses_are_reachable_deterministic_and_better_than_random() {
    for name in ["ranger-mk1", "ur5"] {
        let config = robot(name);
        let chain = Chain::new(&config);
        let workspace = Workspace::new(&config.workspace);
        let planned = plan::plan(&config, FitSet::All, MeasuredIn::Instrument, 30, 600, 4).unwrap();
        assert_eq!(planned.poses.len(), 30);
        for q in &planned.poses {
            assert!(chain.within_limits(q));
            assert!(workspace.allows(&chain.forward(q).unwrap().translation.vector));
        }
        let again = plan::plan(&config, FitSet::All, MeasuredIn::Instrument, 30, 600, 4).unwrap();
        assert_eq!(planned.poses, again.poses);

        // Against 30 random poses: better observability and conditioning.
        let random = plan::random_poses(&config, 30, 99).unwrap();
        let g = Geometry::new(&config);
        let chance = identify::analyse(
            &g,
            &g.candidates(FitSet::All, MeasuredIn::Instrument),
            &random,
        );
        let a = &planned.analysis;
        println!(
            "{name}: planned O1 {:.3} cond {:.1}; random O1 {:.3} cond {:.1}",
            a.observability, a.condition, chance.observability, chance.condition
        );
        assert_eq!(a.identified, chance.identified);
        assert!(a.observability > chance.observability);
        assert!(a.condition < chance.condition);
    }
}

#[test]
fn a_redundant_parameter_has_a_zero_singular_value() {
    // Every unidentifiable candidate leaves one (numerically) zero singular value.
    let config = robot("ur5");
    let g = Geometry::new(&config);
    let poses = plan::random_poses(&config, 40, 3).unwrap();
    let a = identify::analyse(
        &g,
        &g.candidates(FitSet::All, MeasuredIn::Instrument),
        &poses,
    );
    let largest = a.singular_values[0];
    let zero = a
        .singular_values
        .iter()
        .filter(|s| **s < 1e-8 * largest)
        .count();
    assert_eq!(zero, a.unidentifiable.len());
    assert!(a.singular_values[a.identified.len() - 1] > 1e-3 * largest);
}
