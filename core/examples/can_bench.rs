//! CAN bench: set-point rate, bus load and latency of PT streaming to simulated Whistles,
//! both schedules side by side (interpreter: `QP` writes and queries; PDO: SYNC and one
//! receive and one transmit PDO per drive), six drives (ranger-mk1) and eight (ranger-mk2), at
//! 500 kbit/s and 1 Mbit/s, each at the fastest control period under 70 % load.
//!
//! ```sh
//! cargo run --release -p armgate-core --example can_bench [-- --plots DIR] [-- --soak SECONDS]
//! ```
//!
//! For each row the load model ([`armgate_core::config::bus_load`]) picks the fastest period
//! (a whole number of 360 µs drive samples) whose worst-case load stays under 70 %; the
//! controller then drives the arm through a joint move (and on ranger-mk1 a Cartesian circle)
//! for 30 s of simulated time on the virtual bus, and the table reports what the bus and the
//! drives saw. The soak runs then stream the PDO schedule at both bit rates for 10 minutes of
//! simulated time each (`--soak SECONDS` to change it) with the drives' clocks off by up to
//! ±100 ppm, without and with 1 % of the frames lost at random (`--loss-seed N` for another
//! loss pattern), for several fixed leads and the robot file's default (the adaptive lead),
//! on ranger-mk1 and, at the defaults, ranger-mk2. With `--plots DIR`, `can-bench.svg`
//! shows the six-drive rows per control cycle: the bus load and the mean write-to-reached
//! latency of the PT points reached in that cycle.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant // the seed's home angles, as it wrote them
)]

use std::path::{Path, PathBuf};

#[path = "../tests/drives_rig/mod.rs"]
mod drives_rig;
use drives_rig::Rig;

use armgate_core::config::bus_load::DEFAULT_CEILING;
use armgate_core::config::{PDO_TARGET_LEAD, TIME_STAMP_EVERY};
use armgate_core::config::{Streaming, ValidRobot, load_file};
use armgate_core::drives::streaming::PDO_LEAD_RAISE;
use armgate_core::drives::{DriveSettings, DriveState, DriveStats};
use armgate_core::motion::{Mode, Shape};
use armgate_core::sim::{BusStats, VirtualBus};
use armgate_plot::{Figure, Panel, Series, write_svg};

const READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];
const RUN_SECONDS: f64 = 30.0;
const BITRATES: [u32; 2] = [500_000, 1_000_000];

fn main() {
    let plots = armgate_plot::plots_dir_from_args().unwrap();
    let settings = DriveSettings::default();
    let mut header = true;
    let mut runs = Vec::new();
    for streaming in [Streaming::Interpreter, Streaming::Pdo] {
        let model = settings.load_model(&robot("ranger-mk1", streaming));
        println!(
            "{streaming:?} schedule: per drive and cycle {} bits worst case, plus {:.1} per cycle{}",
            model.bits_per_drive(),
            model.bits_per_cycle_shared(),
            match streaming {
                Streaming::Interpreter => " (QP + echo, query + answer)".to_string(),
                Streaming::Pdo => format!(
                    " (RPDO3 + TPDO3; SYNC and a Time Stamp every {} cycles) and a temperature query + answer per drive every {} cycles",
                    model.time_stamp_every, settings.schedule.temperature_every
                ),
            }
        );
    }
    println!();
    for name in ["ranger-mk1", "ranger-mk2"] {
        for bitrate in BITRATES {
            for streaming in [Streaming::Interpreter, Streaming::Pdo] {
                let base = robot(name, streaming);
                let model = settings.load_model(&base);
                let fastest = model.fastest_period(bitrate, DEFAULT_CEILING).unwrap();
                let config = base
                    .edit(|config| {
                        config.drives.can_bitrate = bitrate;
                        config.control_period = fastest.period;
                    })
                    .expect("the fastest period keeps under the default ceiling");
                let r = run(
                    &config,
                    &settings,
                    VirtualBus::for_robot(&config),
                    RUN_SECONDS,
                );
                if header {
                    println!(
                        "| robot, drives | schedule | bit rate | period | set-point rate | load, worst-case stuffing (model / bus) | load, actual stuffing (bus) | lead | latency write → reached | latency step → reached | start skew: BG / first sample | underflows | points skipped / inserted |"
                    );
                    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
                    header = false;
                }
                println!(
                    "| {name}, {} | {} | {} kbit/s | {:.2} ms ({} × 360 µs) | {:.1} Hz | {:.1} % / {:.1} % | {:.1} % | {} | ≤ {:.2} set-points = {:.1} ms | ≤ {:.1} ms | {:.0} µs / {:.0} µs | {} | {} / {} |",
                    model.drives,
                    schedule_name(streaming),
                    bitrate / 1000,
                    fastest.period * 1e3,
                    fastest.samples,
                    1.0 / fastest.period,
                    fastest.load * 100.0,
                    r.worst_load * 100.0,
                    r.typical_load * 100.0,
                    r.leads,
                    r.latency_max / fastest.period,
                    r.latency_max * 1e3,
                    (r.latency_max + r.write_delay_max) * 1e3,
                    r.skew * 1e6,
                    r.first_sample_skew * 1e6,
                    r.underflows,
                    r.stats.points_skipped,
                    r.stats.points_inserted,
                );
                if name == "ranger-mk1" {
                    runs.push((bitrate, streaming, fastest.period, r));
                }
            }
        }
    }
    if let Some(dir) = &plots {
        plot_cycles(dir, &runs);
    }
    let seconds = soak_seconds();
    println!();
    println!(
        "PDO schedule, {seconds:.0} s of simulated time, drive clocks within ±100 ppm (0 ppm: clocks that agree), locked by Time Stamps or not, frames lost at random from power-on (the first start and the restarts too), consumer heartbeat time 350 ms, joint moves back and forth; a fault is counted and the drives restarted:"
    );
    println!();
    println!(
        "| robot, drives | bit rate | period | drive clocks | Time Stamps | frame loss | lead (`pdo_lead` + up to `pdo_lead_raise`) | leads kept | points lost; lead raised / lowered; points skipped / inserted | frames lost | faults (restarted, with loss); requests repeated in the restarts; restarts failed | underflows | latency write → reached |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    // (robot, drive clocks ±ppm, frame loss, (pdo_lead, pdo_lead_raise), time_stamp_every);
    // `DEFAULT` and `STAMPED`: the robot file's defaults, `UNLOCKED`: no Time Stamps.
    const DEFAULT: (u16, u16) = (PDO_TARGET_LEAD, PDO_LEAD_RAISE);
    const STAMPED: Option<u16> = None;
    const UNLOCKED: Option<u16> = Some(0);
    let cases = [
        ("ranger-mk1", 0.0, 0.0, (1, 0), STAMPED),
        ("ranger-mk1", 100.0, 0.0, (1, 0), STAMPED),
        ("ranger-mk1", 100.0, 0.0, (1, 0), UNLOCKED),
        ("ranger-mk1", 100.0, 0.0, (2, 0), UNLOCKED),
        ("ranger-mk1", 0.0, 0.0, DEFAULT, STAMPED),
        ("ranger-mk1", 100.0, 0.0, DEFAULT, STAMPED),
        ("ranger-mk1", 100.0, 0.0, DEFAULT, UNLOCKED),
        ("ranger-mk1", 0.0, 0.0, (3, 2), STAMPED),
        ("ranger-mk1", 100.0, 0.0, (3, 2), STAMPED),
        ("ranger-mk1", 100.0, 0.01, (2, 0), STAMPED),
        ("ranger-mk1", 100.0, 0.01, (3, 0), STAMPED),
        ("ranger-mk1", 100.0, 0.01, (4, 0), STAMPED),
        ("ranger-mk1", 100.0, 0.01, DEFAULT, STAMPED),
        ("ranger-mk1", 100.0, 0.01, DEFAULT, UNLOCKED),
        ("ranger-mk1", 100.0, 0.01, (3, 2), STAMPED),
        ("ranger-mk2", 0.0, 0.0, DEFAULT, STAMPED),
        ("ranger-mk2", 100.0, 0.0, DEFAULT, STAMPED),
        ("ranger-mk2", 100.0, 0.0, DEFAULT, UNLOCKED),
        ("ranger-mk2", 100.0, 0.01, (4, 0), STAMPED),
        ("ranger-mk2", 100.0, 0.01, DEFAULT, STAMPED),
        ("ranger-mk2", 100.0, 0.01, (3, 2), STAMPED),
    ];
    for bitrate in BITRATES {
        for (name, ppm, loss, (lead, raise), stamps) in cases {
            // 350 ms consumer heartbeat time: two heartbeats lost in a row (1 in 10,000 at 1 %
            // loss) would exceed the default 300 ms and stop a drive (ER36), which is not what
            // the soak measures.
            let settings = DriveSettings {
                heartbeat_timeout: 0.35,
                ..DriveSettings::default()
            };
            let base = robot(name, Streaming::Pdo)
                .edit(|config| config.drives.time_stamp_every = stamps)
                .unwrap();
            let fastest = settings
                .load_model(&base)
                .fastest_period(bitrate, DEFAULT_CEILING)
                .unwrap();
            let config = base
                .edit(|config| {
                    config.drives.can_bitrate = bitrate;
                    config.control_period = fastest.period;
                    // The robot file's keys; none where the row is its default.
                    if (lead, raise) != DEFAULT {
                        config.drives.pdo_lead = Some(lead);
                        config.drives.pdo_lead_raise = Some(raise);
                    }
                })
                .unwrap();
            let s = soak(&config, &settings, seconds, ppm, loss);
            let setting = if (lead, raise) == DEFAULT {
                format!("{lead} + {raise} (default)")
            } else if raise == 0 {
                format!("{lead} fixed")
            } else {
                format!("{lead} + {raise}")
            };
            println!(
                "| {name}, {} | {} kbit/s | {:.2} ms | ±{ppm:.0} ppm | {} | {:.0} % | {setting} | {:?} | {}; {} / {}; {} / {} | {} | {} {:?}; {}; {} {:?} | {} | ≤ {:.2} set-points = {:.1} ms (mean {:.2}) |",
                config.dof(),
                bitrate / 1000,
                fastest.period * 1e3,
                match stamps {
                    STAMPED => format!("after every {TIME_STAMP_EVERY} SYNCs (default)"),
                    _ => "none".to_string(),
                },
                loss * 100.0,
                s.leads,
                s.stats.points_lost,
                s.stats.lead_raised,
                s.stats.lead_lowered,
                s.stats.points_skipped,
                s.stats.points_inserted,
                s.frames_lost,
                s.faults.len(),
                s.faults.iter().take(3).collect::<Vec<_>>(),
                s.restarts_repeated,
                s.failed_starts.len(),
                s.failed_starts.iter().take(3).collect::<Vec<_>>(),
                s.underflows,
                s.latency_max / fastest.period,
                s.latency_max * 1e3,
                s.latency_total_ns as f64 * 1e-9 / s.latency_points.max(1) as f64 / fastest.period,
            );
        }
    }
    let seed = robot("ranger-mk1", Streaming::Interpreter).control_period;
    println!();
    println!(
        "seed schedule (spec §6.5): 60 frames per {:.2} ms at 500 kbit/s = {:.1} % worst case; latency 5 points = {:.0} ms",
        seed * 1e3,
        seed_load(seed, 500_000) * 100.0,
        5.0 * seed * 1e3
    );
}

fn schedule_name(streaming: Streaming) -> &'static str {
    match streaming {
        Streaming::Interpreter => "interpreter",
        Streaming::Pdo => "PDO",
    }
}

/// `robots/<name>.toml` on `streaming`.
fn robot(name: &str, streaming: Streaming) -> ValidRobot {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../robots/{name}.toml"));
    load_file(&path)
        .expect("robot file")
        .edit(|config| config.drives.streaming = streaming)
        .expect("the robot file's period carries both schedules")
}

/// `--soak SECONDS`, or 10 minutes.
fn soak_seconds() -> f64 {
    option("--soak").map_or(600.0, |v| v.parse().expect("--soak SECONDS"))
}

/// `--loss-seed N`: the seed of the soak's frame loss (default 11); restarts use the next ones.
fn loss_seed() -> u64 {
    option("--loss-seed").map_or(11, |v| v.parse().expect("--loss-seed N"))
}

/// The value after `flag` on the command line.
fn option(flag: &str) -> Option<String> {
    let mut args = std::env::args();
    args.position(|a| a == flag)?;
    args.next()
}

struct Soak {
    frames_lost: u64,
    /// Start-step requests sent again during the restarts.
    restarts_repeated: u32,
    /// Restarts that faulted before the `BG`.
    failed_starts: Vec<String>,
    faults: Vec<String>,
    underflows: u32,
    latency_max: f64,
    /// Points reached and their write-to-reached times summed (ns), for the mean.
    latency_points: u64,
    latency_total_ns: u64,
    /// The leads the stream kept (`DriveManager::pdo_lead_now`) while streaming.
    leads: std::collections::BTreeSet<u16>,
    /// The manager's counters at the end.
    stats: DriveStats,
}

/// The PDO schedule for `seconds` with `loss` of the frames lost and the drives' clocks spread
/// over ±`max_ppm`: joint moves back and forth; a fault is counted and the drives restarted with
/// the loss on (the stop's frames are not repeated: no loss while the drives stop).
fn soak(
    config: &ValidRobot,
    settings: &DriveSettings,
    seconds: f64,
    max_ppm: f64,
    loss: f64,
) -> Soak {
    let mut bus = VirtualBus::for_robot(config);
    bus.spread_clock_errors(max_ppm, 7);
    // Lossy from power-on: the first start runs with the loss too.
    bus.set_frame_loss(loss, loss_seed());
    let mut l = Rig::on(config.clone(), settings, bus);
    l.manager_mut().start().unwrap();
    l.until(2000, |r| r.manager().state() != DriveState::Starting);
    assert_eq!(l.manager().state(), DriveState::Operational);
    l.ticks(20);
    // What the first start and its first cycles lost and underflowed counts; the latency of
    // its fill points does not.
    let (start_lost, start_underflows) = (
        l.bus().stats().frames_lost,
        l.bus().drives().map(|d| d.stats().underflows).sum::<u32>(),
    );
    l.bus_mut().reset_stats();
    l.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let start = l.now;
    let home = config.home();
    let mut soak = Soak {
        frames_lost: start_lost,
        restarts_repeated: 0,
        failed_starts: Vec::new(),
        faults: Vec::new(),
        underflows: start_underflows,
        latency_max: 0.0,
        latency_points: 0,
        latency_total_ns: 0,
        leads: Default::default(),
        stats: DriveStats::default(),
    };
    let away = away_from_home(config);
    let mut there = false;
    while l.now - start < seconds {
        if l.manager().is_operational() {
            soak.leads.insert(l.manager().pdo_lead_now());
        }
        if l.manager().is_operational() && !l.ctrl().is_moving() {
            let goal: &[f64] = if there { &home } else { &away };
            l.ctrl_mut().move_joints(goal, 0.0).unwrap();
            there = !there;
        }
        l.tick();
        if let Some(fault) = l.manager().fault() {
            soak.faults.push(fault.text().as_str().to_string());
            // The stop's frames (the hold points, `ST`) are not repeated either.
            let lost_so_far = l.bus().stats().frames_lost;
            l.bus_mut().set_frame_loss(0.0, 0);
            l.until(100, |r| r.manager().state() == DriveState::Faulted);
            soak.add(l.bus(), lost_so_far);
            l.bus_mut().reset_stats();
            // The restart runs with the loss on: its steps repeat a request whose answer
            // was lost.
            l.bus_mut()
                .set_frame_loss(loss, soak.faults.len() as u64 + loss_seed());
            let repeated_before = l.manager().stats().requests_repeated;
            l.manager_mut().start().unwrap();
            l.until(2000, |r| r.manager().state() != DriveState::Starting);
            // A fault after the `BG` (a lost point at a short lead) is counted by the loop
            // like any other; one before it is a start that failed (and is tried again).
            let begun = l.bus().drives().all(|d| d.stats().begun_at.is_some());
            if let (Some(fault), false) = (l.manager().fault(), begun) {
                soak.failed_starts.push(fault.text().as_str().to_string());
            }
            soak.restarts_repeated += l.manager().stats().requests_repeated - repeated_before;
            l.ticks(20);
            // What the start and its first cycles lost and underflowed counts; the latency of
            // the start's fill points does not.
            soak.frames_lost += l.bus().stats().frames_lost;
            soak.underflows += l.bus().drives().map(|d| d.stats().underflows).sum::<u32>();
            l.bus_mut().reset_stats();
        }
    }
    soak.add(l.bus(), l.bus().stats().frames_lost);
    soak.stats = l.manager().stats();
    soak
}

/// Where the joint moves go: the ready pose on six joints, every joint 0.3 rad off home on
/// more.
fn away_from_home(config: &ValidRobot) -> Vec<f64> {
    if config.dof() == 6 {
        READY.to_vec()
    } else {
        config.home().iter().map(|q| q + 0.3).collect()
    }
}

impl Soak {
    /// Adds one stretch of streaming: `lost` frames, and what the drives counted.
    fn add(&mut self, bus: &VirtualBus, lost: u64) {
        self.frames_lost += lost;
        self.underflows += bus.drives().map(|d| d.stats().underflows).sum::<u32>();
        let latency = bus
            .drives()
            .map(|d| d.stats().latency.max_ns)
            .max()
            .unwrap();
        self.latency_max = self.latency_max.max(latency as f64 * 1e-9);
        let (points, total_ns) = latency_totals(bus);
        self.latency_points += points;
        self.latency_total_ns += total_ns;
    }
}

struct Outcome {
    worst_load: f64,
    typical_load: f64,
    leads: String,
    latency_max: f64,
    write_delay_max: f64,
    skew: f64,
    first_sample_skew: f64,
    stats: DriveStats,
    underflows: u32,
    cycles: Vec<Cycle>,
}

/// What one control cycle put on the bus, and what the drives reached in it.
struct Cycle {
    /// Time since the start of the run (s).
    t: f64,
    /// Bus load, actual and with worst-case stuffing.
    load: f64,
    worst_load: f64,
    /// Mean write-to-reached time of the PT points reached in the cycle (s); none if none.
    latency: Option<f64>,
}

/// The latency counters summed over the drives: (points, total ns).
fn latency_totals(bus: &VirtualBus) -> (u64, u64) {
    bus.drives().fold((0, 0), |(n, ns), d| {
        let l = d.stats().latency;
        (n + l.points, ns + l.total_ns)
    })
}

/// The control loop on `bus`: drive manager and controller, stepped once per period for
/// `seconds` of simulated time: a joint move, then (six joints) a circle, or (more) a move back.
fn run(config: &ValidRobot, settings: &DriveSettings, bus: VirtualBus, seconds: f64) -> Outcome {
    let mut l = Rig::started(config, settings, bus);
    let begun: Vec<u64> = l
        .bus()
        .drives()
        .filter_map(|d| d.stats().begun_at)
        .collect();
    let skew = (begun.iter().max().unwrap() - begun.iter().min().unwrap()) as f64 * 1e-9;
    let first_sample_skew = l.bus().start_skew_ns().unwrap() as f64 * 1e-9;
    l.bus_mut().reset_stats();
    let start = l.now;
    l.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let six = config.dof() == 6;
    // Eight joints: every joint 0.3 rad off home (all are within ±π).
    l.ctrl_mut()
        .move_joints(&away_from_home(config), 0.0)
        .unwrap();
    let mut leads = std::collections::BTreeSet::new();
    let mut circle_started = false;
    let mut write_delay_max: f64 = 0.0;
    let mut cycles = Vec::new();
    let (mut bus_before, mut latency_before) = (l.bus().stats(), latency_totals(l.bus()));
    while l.now - start < seconds {
        let step_time = l.now;
        l.tick();
        let (bus, latency) = (l.bus().stats(), latency_totals(l.bus()));
        let cycle = BusStats {
            bits: bus.bits - bus_before.bits,
            worst_case_bits: bus.worst_case_bits - bus_before.worst_case_bits,
            elapsed_ns: bus.elapsed_ns - bus_before.elapsed_ns,
            ..bus
        };
        let points = latency.0 - latency_before.0;
        cycles.push(Cycle {
            t: l.now - start,
            load: cycle.load(config.drives.can_bitrate),
            worst_load: cycle.worst_case_load(config.drives.can_bitrate),
            latency: (points > 0)
                .then(|| (latency.1 - latency_before.1) as f64 * 1e-9 / points as f64),
        });
        (bus_before, latency_before) = (bus, latency);
        // The points sent at the last step have been written by now: how long after it.
        for drive in l.bus().drives() {
            let written = drive.table().last_write().unwrap() as f64 * 1e-9;
            write_delay_max = write_delay_max.max(written - step_time);
        }
        assert!(l.manager().is_operational(), "{:?}", l.manager().fault());
        (0..config.dof())
            .filter_map(|j| l.manager().lead(j))
            .for_each(|lead| {
                leads.insert(lead);
            });
        let idle = !l.ctrl().is_moving() && l.now - start > 1.0;
        if idle && !six && !circle_started {
            l.ctrl_mut().move_joints(&config.home(), 0.0).unwrap();
            circle_started = true;
        }
        if idle && six && !circle_started {
            l.ctrl_mut().set_mode(Mode::Cartesian).unwrap();
            l.ctrl_mut()
                .start_shape(Shape::Circle {
                    radius: 0.1,
                    period: 10.0,
                    axis_i: 0,
                    axis_j: 2,
                })
                .unwrap();
            circle_started = true;
        }
    }
    let stats = l.bus().stats();
    let latency_max = l
        .bus()
        .drives()
        .map(|d| d.stats().latency.max_ns)
        .max()
        .unwrap() as f64
        * 1e-9;
    Outcome {
        worst_load: stats.worst_case_load(config.drives.can_bitrate),
        typical_load: stats.load(config.drives.can_bitrate),
        leads: format!("{leads:?}"),
        latency_max,
        write_delay_max,
        skew,
        first_sample_skew,
        stats: l.manager().stats(),
        underflows: l.bus().drives().map(|d| d.stats().underflows).sum(),
        cycles,
    }
}

/// `can-bench.svg`: per cycle, the bus load (actual and worst-case stuffing, against the
/// 70 % ceiling) and the mean latency from writing a PT point to reaching it, per bit rate.
fn plot_cycles(dir: &Path, runs: &[(u32, Streaming, f64, Outcome)]) {
    let mut load = Panel::new("bus load per control cycle", "t (s)", "load (%)").series(
        Series::reference(
            "ceiling",
            [
                (0.0, DEFAULT_CEILING * 100.0),
                (RUN_SECONDS, DEFAULT_CEILING * 100.0),
            ],
        )
        .color(7),
    );
    let mut latency = Panel::new(
        "latency, PT point written → reached (mean of the points reached in the cycle)",
        "t (s)",
        "latency (ms)",
    );
    for (k, (bitrate, streaming, period, r)) in runs.iter().enumerate() {
        let name = format!(
            "{}, {} kbit/s, {:.2} ms period",
            schedule_name(*streaming),
            bitrate / 1000,
            period * 1e3
        );
        load = load
            .series(
                Series::line(
                    format!("{name}, worst-case stuffing"),
                    r.cycles.iter().map(|c| (c.t, c.worst_load * 100.0)),
                )
                .color(2 * k + 1),
            )
            .series(
                Series::line(
                    format!("{name}, actual"),
                    r.cycles.iter().map(|c| (c.t, c.load * 100.0)),
                )
                .color(2 * k),
            );
        latency = latency.series(
            Series::line(
                name,
                r.cycles
                    .iter()
                    .map(|c| (c.t, c.latency.map_or(f64::NAN, |l| l * 1e3))),
            )
            .color(2 * k),
        );
    }
    let figure = Figure::new(
        "CAN bench: ranger-mk1, 6 simulated Whistles, joint move then a 0.1 m circle, both schedules",
        vec![load.include_y(0.0), latency.include_y(0.0)],
    );
    let file = dir.join("can-bench.svg");
    write_svg(&file, &figure).unwrap();
    println!("wrote {}", file.display());
}

/// The seed's schedule: per drive and kinematic period one QP write, four queries and five
/// 8-byte answers (spec §6.5).
fn seed_load(period: f64, bitrate: u32) -> f64 {
    use armgate_protocol::can::{CanFrame, bits_on_wire};
    let frame = |n: usize| bits_on_wire(&CanFrame::new(0x365, &[0; 8][..n]).unwrap());
    let per_drive = frame(8) + 4 * frame(4) + 5 * frame(8);
    f64::from(6 * per_drive) / (period * f64::from(bitrate))
}
