//! The jerk-limited (double-S) profile, checked the way Ruckig checks its own: known cases
//! computed by hand, and many random cases with a fixed seed that must end exactly at the goal,
//! stay within every limit and be time-optimal (or last exactly the requested duration).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use armgate_core::motion::{DoubleS, JerkLimits, ProfileError, RandomCase};
use armgate_core::rng::SplitMix64;

fn close(x: f64, y: f64, tol: f64) -> bool {
    (x - y).abs() <= tol * (1.0 + y.abs())
}

fn assert_state(p: &DoubleS, t: f64, expected: (f64, f64, f64)) {
    let got = p.sample(t);
    assert!(
        close(got.0, expected.0, 1e-12)
            && close(got.1, expected.1, 1e-12)
            && close(got.2, expected.2, 1e-12),
        "at {t}: {got:?}, expected {expected:?}"
    );
}

#[test]
fn reaches_every_limit_when_the_move_is_long() {
    // v = a = j = 1: Tj = 1, Ta = 2, cruise 10/1 − 2 = 8 s, T = 12 s.
    let p = DoubleS::new(10.0, JerkLimits::new(1.0, 1.0, 1.0), 0.0).unwrap();
    assert!(close(p.duration(), 12.0, 1e-15));
    assert_eq!(p.phase_ends(), [1.0, 1.0, 2.0, 10.0, 11.0, 11.0, 12.0]);
    assert_state(&p, 0.5, (0.125 / 6.0, 0.125, 0.5));
    assert_state(&p, 1.0, (1.0 / 6.0, 0.5, 1.0));
    assert_state(&p, 2.0, (1.0, 1.0, 0.0));
    assert_state(&p, 6.0, (5.0, 1.0, 0.0));
    assert_state(&p, 11.5, (10.0 - 0.125 / 6.0, 0.125, -0.5));
    assert_eq!(p.sample(12.0), (10.0, 0.0, 0.0));
    assert_eq!(p.sample(-1.0), (0.0, 0.0, 0.0));
}

#[test]
fn constant_acceleration_phase_and_cruise() {
    // v = 2, a = 1, j = 2: Tj = 0.5, Ta = 0.5 + 2 = 2.5, cruise 10/2 − 2.5 = 2.5, T = 7.5.
    let p = DoubleS::new(-10.0, JerkLimits::new(2.0, 1.0, 2.0), 0.0).unwrap();
    assert!(close(p.duration(), 7.5, 1e-15));
    // In the constant-acceleration phase at t = 1.5: a = 1, v = 1.5 − 0.25, p = 1.125 − 0.375
    // + 0.25/6 (negated: the move goes backwards).
    assert_state(&p, 1.5, (-(1.125 - 0.375 + 0.25 / 6.0), -1.25, -1.0));
    assert_state(&p, 3.75, (-5.0, -2.0, 0.0));
    assert_eq!(p.sample(7.5), (-10.0, 0.0, 0.0));
}

#[test]
fn short_move_reaches_the_acceleration_limit_but_not_the_velocity_limit() {
    // d = 1, v = 10, a = 1, j = 10: Tj = 0.1, Ta = (0.1 + √4.01)/2, no cruise.
    let p = DoubleS::new(1.0, JerkLimits::new(10.0, 1.0, 10.0), 0.0).unwrap();
    let ta = 1.051_249_219_725_039_3;
    assert!(close(p.duration(), 2.0 * ta, 1e-14));
    assert!(close(p.peak_velocity(), ta - 0.1, 1e-14));
    assert!(close(p.peak_acceleration(), 1.0, 1e-15));
    assert_state(&p, ta, (0.5, ta - 0.1, 0.0));
}

#[test]
fn tiny_move_reaches_no_limit() {
    // d = 0.002, j = 10: Tj = ∛(0.002/20), T = 4·Tj, peak acceleration j·Tj < a.
    let p = DoubleS::new(0.002, JerkLimits::new(1.0, 1.0, 10.0), 0.0).unwrap();
    let tj = 0.046_415_888_336_127_79;
    assert!(close(p.duration(), 4.0 * tj, 1e-14));
    assert!(close(p.peak_acceleration(), 10.0 * tj, 1e-14));
    assert!(close(p.peak_velocity(), 10.0 * tj * tj, 1e-14));
    assert_state(&p, 2.0 * tj, (0.001, 10.0 * tj * tj, 0.0));
}

#[test]
fn stretching_at_the_acceleration_limit_solves_the_quadratic() {
    // The 7.5 s move above stretched to 8 s: vp² − 7.5·vp + 10 = 0, vp = (7.5 − √16.25)/2.
    let p = DoubleS::new(10.0, JerkLimits::new(2.0, 1.0, 2.0), 8.0).unwrap();
    assert!(close(p.duration(), 8.0, 1e-14));
    assert!(close(p.peak_velocity(), 1.734_435_562_925_362_6, 1e-14));
    assert!(close(p.peak_acceleration(), 1.0, 1e-15));
    assert_eq!(p.sample(8.0), (10.0, 0.0, 0.0));
    assert_state(&p, 4.0, (5.0, p.peak_velocity(), 0.0));
}

#[test]
fn stretching_below_the_acceleration_limit_solves_the_cubic() {
    // The 12 s move stretched to 20 s: 2·Tj³ − 20·Tj² + 10 = 0 (Tj = 0.7346…), vp = Tj².
    let p = DoubleS::new(10.0, JerkLimits::new(1.0, 1.0, 1.0), 20.0).unwrap();
    let tj = 0.734_603_507_789_303_3;
    assert!(close(p.duration(), 20.0, 1e-14));
    assert!(close(p.peak_velocity(), tj * tj, 1e-14));
    assert!(close(p.peak_acceleration(), tj, 1e-14));
    assert!(close(
        p.phase_ends()[3] - p.phase_ends()[2],
        17.061_585_968_842_787,
        1e-13
    ));
}

#[test]
fn synchronising_keeps_a_shorter_request_and_a_zero_move_rests() {
    let limits = JerkLimits::new(1.0, 1.0, 1.0);
    let p = DoubleS::new(10.0, limits, 0.0).unwrap();
    assert_eq!(p.with_duration(5.0).unwrap(), p);
    assert_eq!(p.with_duration(12.0).unwrap(), p);
    let rest = DoubleS::new(0.0, limits, 3.0).unwrap();
    assert_eq!(rest.duration(), 3.0);
    assert_eq!(rest.sample(1.0), (0.0, 0.0, 0.0));
    assert_eq!(rest.sample(f64::NAN), (0.0, 0.0, 0.0));
}

#[test]
fn bad_inputs_are_typed_errors() {
    let ok = JerkLimits::new(1.0, 1.0, 1.0);
    assert_eq!(
        DoubleS::new(f64::NAN, ok, 0.0),
        Err(ProfileError::InvalidDistance)
    );
    assert_eq!(
        DoubleS::new(f64::INFINITY, ok, 0.0),
        Err(ProfileError::InvalidDistance)
    );
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        for limits in [
            JerkLimits::new(bad, 1.0, 1.0),
            JerkLimits::new(1.0, bad, 1.0),
            JerkLimits::new(1.0, 1.0, bad),
        ] {
            assert_eq!(
                DoubleS::new(1.0, limits, 0.0),
                Err(ProfileError::InvalidLimits)
            );
        }
    }
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(
            DoubleS::new(1.0, ok, bad),
            Err(ProfileError::InvalidDuration)
        );
    }
    let tiny = JerkLimits::new(1e-300, 1e-300, 1e-300);
    assert_eq!(
        DoubleS::new(1e300, tiny, 0.0),
        Err(ProfileError::OutOfRange)
    );
}

/// Relative slack for limits and the final state (the 1e-9).
const TOL: f64 = 1e-9;

/// One random case ([`RandomCase`]: limits over eight decades, a distance of either sign,
/// half of them stretched to 1 + 1e-9 up to 1001 times their minimum time). Panics on any
/// violated property.
fn check_random_case(rng: &mut SplitMix64) {
    let case = RandomCase::draw(rng);
    let (distance, limits) = (case.distance, case.limits);
    let sign = distance.signum();
    let fastest = DoubleS::new(distance, limits, 0.0).unwrap();
    let p = case.plan().unwrap();
    let stretched = case.min_duration > 0.0;
    if stretched {
        let requested = case.min_duration;
        assert!(
            (p.duration() - requested).abs() <= TOL * requested,
            "{distance} {limits:?}: {} instead of {requested}",
            p.duration()
        );
    } else {
        assert_eq!(p, fastest);
    }
    let (v, a, j) = (limits.velocity, limits.acceleration, limits.jerk);
    let t_end = p.duration();
    assert!(t_end >= fastest.duration() * (1.0 - 1e-15));
    // Final state: exact at the end, and reached from the last phase within 1e-9.
    assert_eq!(p.sample(t_end), (distance, 0.0, 0.0));
    let before = p.sample(t_end * (1.0 - 1e-15));
    assert!((before.0 - distance).abs() <= TOL * distance.abs());
    let ends = p.phase_ends();
    // Time-optimal: in each half, the cruise reaches v or is absent, and the acceleration
    // phase reaches a or is absent (the minimum-time profile has no slack left).
    if !stretched {
        let cruise = ends[3] - ends[2];
        let constant_acceleration = ends[1] - ends[0];
        assert!(cruise <= TOL * t_end || p.peak_velocity() >= v * (1.0 - TOL));
        assert!(constant_acceleration <= TOL * t_end || p.peak_acceleration() >= a * (1.0 - TOL));
        assert!(
            p.peak_velocity() >= v * (1.0 - TOL)
                || p.peak_acceleration() >= a * (1.0 - TOL)
                || (constant_acceleration <= TOL * t_end && cruise <= TOL * t_end)
        );
    }
    // Limits and consistency on samples: per phase, its two ends and a random interior point.
    let mut start = 0.0;
    for end in ends {
        assert!(
            end >= start - 1e-15 * t_end,
            "phases out of order: {ends:?}"
        );
        let mid = start + (end - start) * rng.next_f64();
        let s = [p.sample(start), p.sample(mid), p.sample(end)];
        for (x, dx, ddx) in s {
            assert!(dx.abs() <= v * (1.0 + TOL), "{distance} {limits:?}: v {dx}");
            assert!(
                ddx.abs() <= a * (1.0 + TOL),
                "{distance} {limits:?}: a {ddx}"
            );
            // Rest to rest without overshoot: never beyond the goal, never backwards.
            assert!(x * sign >= -TOL * distance.abs() && x * sign <= distance.abs() * (1.0 + TOL));
            assert!(dx * sign >= 0.0);
        }
        // Within a phase velocity is at most quadratic and acceleration linear in time, so
        // Simpson's and the trapezoid rule are exact: position integrates velocity, velocity
        // acceleration, and the acceleration's slope is the jerk limit at most.
        // A sample time is only known to a few units in the last place of the duration (a
        // phase end is a rounded sum), which moves a sample by up to that times its derivative.
        let (h1, h2) = (mid - start, end - mid);
        let h = end - start;
        let dt = 4.0 * f64::EPSILON * t_end;
        if h > 0.0 && h1 > 0.0 && h2 > 0.0 {
            let dv = s[2].1 - s[0].1;
            let trapezoid = 0.5 * h * (s[0].2 + s[2].2);
            let slack = TOL * a * h + 4.0 * (a + j * h) * dt;
            assert!(
                (dv - trapezoid).abs() <= slack,
                "{distance} {limits:?}: {dv} {trapezoid}"
            );
            let da = (s[2].2 - s[0].2).abs();
            assert!(
                da <= j * h * (1.0 + TOL) + 4.0 * j * dt,
                "{distance} {limits:?}: jerk"
            );
            let (m1, m2) = (p.sample(start + 0.5 * h1), p.sample(mid + 0.5 * h2));
            let simpson = h1 / 6.0 * (s[0].1 + 4.0 * m1.1 + s[1].1)
                + h2 / 6.0 * (s[1].1 + 4.0 * m2.1 + s[2].1);
            let slack = TOL * distance.abs() + 4.0 * (v + a * h) * dt;
            assert!(
                (s[2].0 - s[0].0 - simpson).abs() <= slack,
                "{distance} {limits:?}: position does not integrate velocity"
            );
        }
        start = end;
    }
}

/// The CI-sized run: 10⁶ random cases.
#[test]
fn a_million_random_profiles_end_exactly_and_respect_the_limits() {
    let mut rng = SplitMix64::new(0x6a65_726b);
    for _ in 0..1_000_000 {
        check_random_case(&mut rng);
    }
}

/// `cargo test -p armgate-core --release --test jerk_profile -- --ignored`: 10⁸ more.
#[test]
#[ignore]
fn a_hundred_million_random_profiles() {
    let mut rng = SplitMix64::new(0x6a65_726b_0001);
    for _ in 0..100_000_000 {
        check_random_case(&mut rng);
    }
}
