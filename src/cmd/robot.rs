//! `quadcl robot [URDF] [--config FILE] [--seconds 2] [--json]`: what quadcl
//! understood of a robot description, then whether it stands.
//!
//! Prints the legs with their joints (axis, limits, effort limit, standing
//! angle, PD gains), each link's mass after fixed links are merged and the
//! total, the feet, every warning of the loader, and the result of settling
//! the robot under PD at its default pose (`sim::stand_test`). `--config`
//! takes the `[env]` table (robot settings, gains, heights) of a run file or
//! a training config; URDF, when given, replaces its `env.urdf`.

use anyhow::Context;
use clap::Args;
use quadcl::config::bounds::{self, Interval};
use quadcl::config::EnvConfig;
use quadcl::sim::{stand_test, Leg, RobotModel, StandReport};
use serde::Serialize;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct RobotArgs {
    /// The URDF file (default: the config's `env.urdf`, else scenes/a1.urdf).
    pub urdf: Option<PathBuf>,
    /// A run file or training config whose `[env]` describes the robot (default pose, gains, heights).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Seconds to settle the robot at its default pose (in (0, 60]).
    #[arg(long, default_value_t = 2.0)]
    pub seconds: f32,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct JointReport {
    leg: &'static str,
    name: String,
    axis: [f32; 3],
    /// `null` when unlimited.
    limits: Option<[f32; 2]>,
    effort: f32,
    default_angle: f32,
    kp: f32,
    kd: f32,
}

#[derive(Debug, Serialize)]
struct FootReport {
    leg: &'static str,
    calf_link: String,
    offset: [f32; 3],
    radius: f32,
    source: String,
}

#[derive(Debug, Serialize)]
struct Report {
    urdf: String,
    name: String,
    trunk: String,
    joints: Vec<JointReport>,
    feet: Vec<FootReport>,
    /// Each rigid body after merging: (link, mass kg).
    links: Vec<(String, f64)>,
    /// Links folded into another by a fixed joint: (link, into).
    merged: Vec<(String, String)>,
    total_mass: f64,
    warnings: Vec<String>,
    stand: StandReport,
}

pub fn run(args: RobotArgs) -> anyhow::Result<()> {
    bounds::check("--seconds", args.seconds, Interval::OpenClosed(0.0, 60.0))?;
    let mut env = match &args.config {
        Some(path) => quadcl::engine::env_of_file(path)?,
        None => EnvConfig::default(),
    };
    if let Some(urdf) = &args.urdf {
        env.urdf = urdf.display().to_string();
    }
    env.validate().context("the robot's [env] settings")?;
    let robot = RobotModel::for_config(&env)?;
    let stand = stand_test(&env, &robot, args.seconds)
        .with_context(|| format!("settling {} at its default pose", robot.path.display()))?;
    let report = report(&env, &robot, stand)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(&report);
    }
    Ok(())
}

fn report(env: &EnvConfig, robot: &RobotModel, stand: StandReport) -> anyhow::Result<Report> {
    let pose = quadcl::sim::default_pose(env, robot)?;
    let gains = quadcl::sim::joint_gains(env, robot)?;
    let joints = robot
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| JointReport {
            leg: Leg::ALL[i / 3].name(),
            name: j.name.clone(),
            axis: j.axis,
            limits: j.lower.is_finite().then_some([j.lower, j.upper]),
            effort: j.effort,
            default_angle: pose[i],
            kp: gains.kp[i],
            kd: gains.kd[i],
        })
        .collect();
    let feet = Leg::ALL
        .iter()
        .map(|&leg| {
            let l = leg.index();
            FootReport {
                leg: leg.name(),
                calf_link: robot.urdf.links[robot.joints[3 * l + 2].child_link].name.clone(),
                offset: robot.foot_offsets[l],
                radius: robot.foot_radius[l],
                source: robot.foot_sources[l].clone(),
            }
        })
        .collect();
    Ok(Report {
        urdf: robot.path.display().to_string(),
        name: robot.urdf.name.clone(),
        trunk: robot.trunk_name().to_string(),
        joints,
        feet,
        links: robot.urdf.links.iter().map(|l| (l.name.clone(), l.inertial.mass.value)).collect(),
        merged: robot.merged.iter().map(|m| (m.name.clone(), m.into.clone())).collect(),
        total_mass: robot.total_mass,
        warnings: robot.warnings.clone(),
        stand,
    })
}

fn print_text(r: &Report) {
    println!("robot '{}' from {}; trunk link '{}'", r.name, r.urdf, r.trunk);
    println!("legs (leg  joint  axis  limits rad  effort N m  standing rad  kp  kd)");
    for j in &r.joints {
        let limits = j.limits.map_or("unlimited".to_string(), |[lo, hi]| format!("[{lo:.3}, {hi:.3}]"));
        let [x, y, z] = j.axis;
        println!(
            "  {}  {:<20} ({x:.0} {y:.0} {z:.0})  {limits:<16} {:>6.1}  {:>6.3}  {:>5.1}  {:.2}",
            j.leg, j.name, j.effort, j.default_angle, j.kp, j.kd
        );
    }
    println!("feet (in the calf frame)");
    for f in &r.feet {
        let [x, y, z] = f.offset;
        println!(
            "  {}  ({x:.3}, {y:.3}, {z:.3}) m in '{}', radius {:.3} m: {}",
            f.leg, f.calf_link, f.radius, f.source
        );
    }
    println!("rigid bodies after merging fixed links ({}):", r.links.len());
    let line: Vec<String> = r.links.iter().map(|(n, m)| format!("{n} {m:.3}")).collect();
    for chunk in line.chunks(6) {
        println!("  {}", chunk.join(", "));
    }
    let merged_total: f64 = r.links.iter().map(|l| l.1).sum();
    println!("  total {merged_total:.3} kg (the file's links add up to {:.3} kg)", r.total_mass);
    if !r.merged.is_empty() {
        let merged: Vec<String> = r.merged.iter().map(|(a, b)| format!("{a} -> {b}")).collect();
        println!("merged by fixed joints: {}", merged.join(", "));
    }
    println!("warnings: {}", r.warnings.len());
    for w in &r.warnings {
        println!("  {w}");
    }
    let s = &r.stand;
    let feet: Vec<&str> = Leg::ALL.iter().filter(|l| s.feet_in_contact[l.index()]).map(|l| l.name()).collect();
    println!(
        "standing: {:.1} s at the default pose: trunk at {:.3} m (target {:.3}), tilt {:.3} rad, feet on the ground: {}, largest torque {:.1} N m{}: {}",
        s.seconds,
        s.trunk_height,
        s.height_target,
        s.tilt_rad,
        if feet.is_empty() { "none".to_string() } else { feet.join(" ") },
        s.max_torque,
        if s.fell { ", fell" } else { "" },
        if s.stood { "stood" } else { "did NOT stand" }
    );
}
