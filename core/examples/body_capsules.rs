//! The arm's capsules and armgate's distances at random poses, one JSON object per line: the
//! armgate side of `tools/body_crosscheck.py`, which builds the same capsules and boxes in
//! Coal (PyPI `coal`) and compares the distances.
//!
//! `cargo run --release -p armgate-core --example body_capsules -- ROBOT.toml [POSES] [SEED]`
//!
//! Per pose (uniform within the joint limits, placed by the chain's frames as the tick places
//! them): `capsules` (`[link, ax, ay, az, bx, by, bz, radius]`), `boxes` (the robot file's,
//! then one random box of the pose's own, so every robot has a box to check), `pairs`
//! (`[i, j, gap]` for every pair of capsules, checked or not), `box_gaps` (`[i, k, gap]`, every
//! capsule against every box) and `nearest`: the smallest gap of what the body checks, or null
//! for an empty body.
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

use std::io::Write;

use armgate_core::config::{MAX_CAPSULES, load_file};
use armgate_core::geometry::Capsule;
use armgate_core::kinematics::Chain;
use armgate_core::motion::Body;
use armgate_core::rng::SplitMix64;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: body_capsules ROBOT.toml [POSES] [SEED]");
        std::process::exit(2);
    };
    let poses: u32 = args.get(1).map_or(10_000, |n| n.parse().unwrap());
    let seed: u64 = args.get(2).map_or(35, |s| s.parse().unwrap());
    let robot = load_file(path).unwrap();
    let chain = Chain::new(&robot);
    let body = Body::new(&robot);
    let envelope = body.envelope();
    let mut rng = SplitMix64::new(seed);
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    for _ in 0..poses {
        let q = chain.random_joints(&mut rng);
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        assert!(body.place(&chain, &q, &mut placed));
        let capsules = &placed[..envelope.len()];
        let mut boxes: Vec<[f64; 6]> = robot.workspace.boxes.iter().copied().collect();
        let (x, y, z) = (
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-0.2, 1.5),
        );
        let half = [0; 3].map(|_| rng.uniform(0.02, 0.4));
        boxes.push([
            x - half[0],
            x + half[0],
            y - half[1],
            y + half[1],
            z - half[2],
            z + half[2],
        ]);
        let list = |items: Vec<String>| format!("[{}]", items.join(", "));
        let described = capsules
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let (a, b) = (c.segment.a, c.segment.b);
                let link = envelope.link_of(i).unwrap();
                format!(
                    "[{link}, {:?}, {:?}, {:?}, {:?}, {:?}, {:?}, {:?}]",
                    a.x, a.y, a.z, b.x, b.y, b.z, c.radius
                )
            })
            .collect();
        let mut pairs = Vec::new();
        for (i, ci) in capsules.iter().enumerate() {
            for (j, cj) in capsules.iter().enumerate().skip(i + 1) {
                pairs.push(format!("[{i}, {j}, {:?}]", ci.gap_to_capsule(cj)));
            }
        }
        let mut box_gaps = Vec::new();
        for (i, c) in capsules.iter().enumerate() {
            for (k, bx) in boxes.iter().enumerate() {
                box_gaps.push(format!("[{i}, {k}, {:?}]", c.gap_to_box(bx)));
            }
        }
        let (nearest, _) = envelope.nearest(&placed);
        let boxes = boxes.iter().map(|b| format!("{b:?}")).collect();
        writeln!(
            out,
            "{{\"capsules\": {}, \"boxes\": {}, \"pairs\": {}, \"box_gaps\": {}, \"nearest\": {}}}",
            list(described),
            list(boxes),
            list(pairs),
            list(box_gaps),
            if nearest.is_finite() {
                format!("{nearest:?}")
            } else {
                "null".into()
            },
        )
        .unwrap();
    }
}
