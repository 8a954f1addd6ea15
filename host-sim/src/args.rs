//! Checks of the command-line values that clap cannot express by type.

use std::net::{IpAddr, Ipv4Addr, Ipv6Addr};

use armgate_core::command::Network;
use armgate_core::config::ValidRobot;
use armgate_core::kinematics::{Chain, Joints};

/// `--duration`: a finite number of seconds, not negative.
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{s}`: give a number of seconds, 0 or more")),
    }
}

/// The allow-list: loopback always, plus the `--allow` networks (as the README says).
pub fn allow_list(extra: &[Network]) -> Vec<Network> {
    let mut allow = vec![
        Network::new(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 0)), 8),
        Network::new(IpAddr::V6(Ipv6Addr::LOCALHOST), 128),
    ];
    allow.extend_from_slice(extra);
    allow
}

/// `--start` (or the home position): one finite value per joint, each within its limits; a
/// joint outside would be driven back by the limiter on its own.
pub fn start_joints(config: &ValidRobot, start: Option<&[f64]>) -> Result<Joints, String> {
    let home = config.home();
    let chain = Chain::new(config);
    let n = chain.dof();
    let q = chain
        .check(start.unwrap_or(&home))
        .map_err(|e| format!("{e} (the robot has {n} joints)"))?;
    for (k, v) in q.iter().enumerate() {
        let (lo, hi) = (
            chain.min().get(k).copied().unwrap_or(f64::NEG_INFINITY),
            chain.max().get(k).copied().unwrap_or(f64::INFINITY),
        );
        if !(lo..=hi).contains(v) {
            return Err(format!(
                "q{} = {v} is outside the joint's limits [{lo}, {hi}]",
                k + 1
            ));
        }
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::approx_constant)]
    use super::*;

    fn ranger() -> ValidRobot {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        armgate_core::config::load_file(std::path::Path::new(path)).unwrap()
    }

    #[test]
    fn durations_are_finite_and_not_negative() {
        assert_eq!(parse_seconds("2.5"), Ok(2.5));
        assert_eq!(parse_seconds("0"), Ok(0.0));
        for bad in ["nan", "NaN", "-1", "inf", "soon"] {
            assert!(parse_seconds(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn allow_adds_to_loopback() {
        let lab: Network = "192.168.1.0/24".parse().unwrap();
        let list = allow_list(&[lab]);
        assert_eq!(list.len(), 3);
        // Printed as the README writes it.
        assert_eq!(list[0].to_string(), "127.0.0.0/8");
        for ip in ["127.0.0.1", "::1", "192.168.1.7"] {
            let ip: IpAddr = ip.parse().unwrap();
            assert!(list.iter().any(|n| n.contains(ip)), "{ip}");
        }
    }

    #[test]
    fn start_outside_the_limits_is_refused() {
        let config = ranger();
        assert!(start_joints(&config, None).is_ok());
        let ok = [1.5708, 0.0, 1.5708, 0.0, 1.0, 0.0];
        assert!(start_joints(&config, Some(&ok)).is_ok());
        let low_q5 = [1.5708, 0.0, 1.5708, 0.0, 0.3, 0.0];
        assert_eq!(
            start_joints(&config, Some(&low_q5)).unwrap_err(),
            "q5 = 0.3 is outside the joint's limits [0.785, 3.926]"
        );
        assert!(start_joints(&config, Some(&[0.0; 5])).is_err());
        assert!(start_joints(&config, Some(&[f64::NAN; 6])).is_err());
    }
}
