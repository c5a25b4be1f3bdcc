//! The robot in Rerun: a recorder that streams one env's steps to a live
//! viewer (gRPC), to an `.rrd` file, or to both. The static scene (robot,
//! ground, task, masks) is in `rerun_scene`; every control step logs, on the
//! `sim_time` timeline (simulated seconds):
//!
//! | entity | archetype | content |
//! | --- | --- | --- |
//! | `transforms` | `Transform3D` x 13 | world to the URDF's root link (the floating base), then one per leg joint (parent link to child link at the joint's angle, `UrdfTree::compute_joint_transform`) |
//! | `world/feet` | `Points3D` | the four foot points, green in contact, grey in the air |
//! | `world/command`, `world/velocity` | `Arrows3D` | the commanded and the actual horizontal base velocity, from the trunk |
//! | `world/push` | `Arrows3D` | a push's velocity change, shown for 0.5 s |
//! | `reward/total`, `reward/terms` | `Scalars` | the step reward and each term (METHOD Table 1) |
//! | `tracking/lin_vel_err`, `tracking/ang_vel_err` | `Scalars` | \|command - trunk\| in (vx, vy), m/s, and in wz, rad/s |
//! | `joints/position`, `joints/torque` | `Scalars` x 12 | joint angles (rad) and torques (N m), one series per joint |
//! | `command`, `base_velocity` | `Scalars` x 3 | (vx, vy, wz), trunk frame |
//!
//! A file is written under `FILE.rrd.partial` and renamed when the recording
//! finishes, so a file of the final name is always a complete recording. A
//! viewer that cannot be reached is an error within [`CONNECT_WAIT`], never a hang.

use super::recorder::{Recorder, SampleWriter};
use super::rerun_scene::{blueprint, log_scene, RerunRobot, RerunScene};
use super::sample::Sample;
use crate::sim::reward::TERM_NAMES;
use crate::sim::RobotModel;
use ::rerun::sink::{FileSink, GrpcSink, GrpcSinkConnectionState, LogSink};
use ::rerun::RecordingStream;
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The timeline every step is logged on: simulated seconds.
pub const TIMELINE: &str = "sim_time";

/// How long a viewer has to accept the connection.
pub const CONNECT_WAIT: Duration = Duration::from_secs(3);

/// How to get the viewer installed, for messages.
pub const VIEWER_INSTALL: &str = "pip install rerun-sdk==0.36.*, or cargo install rerun-cli --version 0.36.*";

/// Where a Rerun recording goes (two at once are allowed: a live viewer and a file).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RerunSink {
    /// A running viewer at this gRPC URL (`rerun+http://HOST:PORT/proxy`).
    Connect(String),
    /// Start a viewer (`rerun` on PATH) and stream to it.
    Spawn,
    /// An `.rrd` file.
    Save(PathBuf),
}

impl RerunSink {
    /// The viewer's own default address.
    pub fn default_url() -> String {
        ::rerun::DEFAULT_CONNECT_URL.to_string()
    }
}

/// The writing side, on the recorder's thread.
struct RerunWriter {
    rec: RecordingStream,
    robot: RerunRobot,
    /// (partial, final) path of the file sink, if any.
    file: Option<(PathBuf, PathBuf)>,
    /// Whether a live viewer is among the sinks.
    live: bool,
    /// The implicit frame of the entity tree's root: the floating base's parent.
    world_frame: ::rerun::components::TransformFrameId,
    /// When the shown push arrow is cleared.
    push_until: Option<f64>,
    error: Option<anyhow::Error>,
}

impl Recorder {
    /// Records to the Rerun `sinks` (at least one) for `robot`, with `scene`'s static content.
    /// An unreachable viewer, a viewer that cannot be started, a file that cannot be created and
    /// a URDF Rerun cannot read are errors now.
    pub fn rerun(sinks: &[RerunSink], robot: &RobotModel, scene: &RerunScene) -> anyhow::Result<Self> {
        anyhow::ensure!(!sinks.is_empty(), "a Rerun recording needs a sink: --connect, --spawn or --save FILE.rrd");
        let rerun_robot = RerunRobot::of(robot)?;
        let mut boxed: Vec<Box<dyn LogSink>> = Vec::new();
        let (mut file, mut live) = (None, false);
        for sink in sinks {
            match sink {
                RerunSink::Connect(url) => {
                    boxed.push(Box::new(connect(url)?));
                    live = true;
                }
                RerunSink::Spawn => {
                    let port = spawn_viewer()?;
                    boxed.push(Box::new(connect(&format!("rerun+http://127.0.0.1:{port}/proxy"))?));
                    live = true;
                }
                RerunSink::Save(path) => {
                    let partial = partial_path(path);
                    let sink = FileSink::new(&partial)
                        .with_context(|| format!("creating the Rerun recording {}", partial.display()))?;
                    boxed.push(Box::new(sink));
                    file = Some((partial, path.clone()));
                }
            }
        }
        let rec = ::rerun::RecordingStreamBuilder::new("quadcl")
            .recording_name(format!("{} · {}", scene.task, scene.policy))
            .with_blueprint(blueprint(scene))
            .set_sinks(boxed)
            .context("starting the Rerun recording")?;
        log_scene(&rec, &rerun_robot, scene)?;
        for (entity, names) in [
            ("reward/terms", TERM_NAMES.iter().map(|s| s.to_string()).collect::<Vec<_>>()),
            ("joints/position", robot.joints.iter().map(|j| j.name.clone()).collect()),
            ("joints/torque", robot.joints.iter().map(|j| j.name.clone()).collect()),
            ("command", ["vx", "vy", "wz"].map(String::from).to_vec()),
            ("base_velocity", ["vx", "vy", "wz"].map(String::from).to_vec()),
        ] {
            rec.log_static(entity, &::rerun::SeriesLines::new().with_names(names))?;
        }
        let world_frame = ::rerun::components::TransformFrameId::from_entity_path(&::rerun::EntityPath::root());
        let writer = RerunWriter { rec, robot: rerun_robot, file, live, world_frame, push_until: None, error: None };
        Ok(Recorder::start(writer, "Rerun"))
    }
}

/// `FILE.rrd` is written as `FILE.rrd.partial`.
fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// A gRPC sink to `url` once a viewer there accepted the connection; an error after
/// [`CONNECT_WAIT`] without one.
fn connect(url: &str) -> anyhow::Result<GrpcSink> {
    let uri: ::rerun::external::re_uri::ProxyUri = url
        .parse()
        .map_err(|e| anyhow::anyhow!("{url:?} is not a Rerun viewer address like {}: {e}", RerunSink::default_url()))?;
    let no_viewer = || {
        anyhow::anyhow!(
            "no Rerun viewer answers at {url}: start one with `rerun` (to install it: {VIEWER_INSTALL}), \
             pass --spawn to start it, or record to a file with --save FILE.rrd"
        )
    };
    // Nothing listening is known at once (a gRPC client would retry, and wait on drop).
    let address = (uri.origin.format_host(), uri.origin.port);
    let listening = std::net::ToSocketAddrs::to_socket_addrs(&address)
        .map_err(|e| no_viewer().context(format!("resolving {}: {e}", uri.origin)))?
        .any(|a| std::net::TcpStream::connect_timeout(&a, CONNECT_WAIT).is_ok());
    if !listening {
        return Err(no_viewer());
    }
    let sink = GrpcSink::new(uri);
    let start = Instant::now();
    loop {
        match sink.status() {
            GrpcSinkConnectionState::Connected => return Ok(sink),
            GrpcSinkConnectionState::Disconnected(reason) => {
                anyhow::bail!("the Rerun viewer at {url} closed the connection ({reason:?})")
            }
            GrpcSinkConnectionState::Connecting { .. } if start.elapsed() >= CONNECT_WAIT => {
                return Err(no_viewer().context(format!("{url} accepts connections but no gRPC stream")))
            }
            GrpcSinkConnectionState::Connecting { .. } => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

/// How long a started viewer has to open its port.
const SPAWN_WAIT: Duration = Duration::from_secs(10);

/// The port of a viewer on this machine: one already listening on the viewer's default port, or
/// one started from PATH (`rerun --port P --expect-data-soon`, its output discarded so that it
/// cannot draw over the workbench, in its own process group so that it outlives us).
fn spawn_viewer() -> anyhow::Result<u16> {
    let port = ::rerun::DEFAULT_SERVER_PORT;
    let address = std::net::SocketAddr::from(([127, 0, 0, 1], port));
    let listening = || std::net::TcpStream::connect_timeout(&address, Duration::from_millis(200)).is_ok();
    if listening() {
        return Ok(port);
    }
    let exe = std::env::var_os("PATH")
        .and_then(|paths| std::env::split_paths(&paths).map(|d| d.join("rerun")).find(|p| p.is_file()))
        .with_context(|| {
            format!(
                "--spawn: no `rerun` viewer on PATH (to install it: {VIEWER_INSTALL}), \
                 or record to a file with --save FILE.rrd and open that later"
            )
        })?;
    let mut command = std::process::Command::new(&exe);
    command
        .args([format!("--port={port}"), "--expect-data-soon".to_string()])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(&mut command, 0);
    command.spawn().with_context(|| format!("--spawn: starting {}", exe.display()))?;
    let start = Instant::now();
    while start.elapsed() < SPAWN_WAIT {
        if listening() {
            return Ok(port);
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    anyhow::bail!(
        "--spawn: {} started but opened no port {port} within {} s (no display?); \
         record to a file with --save FILE.rrd and open that later",
        exe.display(),
        SPAWN_WAIT.as_secs()
    )
}

/// `v` (a trunk-frame vector) in the world frame, for the trunk orientation `quat` (x, y, z, w).
fn rotate_out_of_frame(quat: [f32; 4], v: [f32; 3]) -> [f32; 3] {
    let [x, y, z, w] = quat;
    crate::sim::obs::rotate_into_frame([-x, -y, -z, w], v)
}

impl RerunWriter {
    fn log_step(&mut self, s: &Sample) -> anyhow::Result<()> {
        let rec = &self.rec;
        rec.set_duration_secs(TIMELINE, s.t);
        let trunk = s.links[0];
        rec.log(
            "transforms",
            &::rerun::Transform3D::update_fields()
                .with_translation(trunk.translation)
                .with_quaternion(trunk.rotation)
                .with_parent_frame(self.world_frame.clone())
                .with_child_frame(self.robot.root_frame.as_str()),
        )?;
        for (joint, q) in self.robot.leg_joints.iter().zip(s.q) {
            let transform = self.robot.tree.compute_joint_transform(joint, f64::from(q), false)?;
            rec.log("transforms", &transform)?;
        }
        let green = ::rerun::Color::from_rgb(60, 210, 90);
        let grey = ::rerun::Color::from_rgb(150, 150, 150);
        rec.log(
            "world/feet",
            &::rerun::Points3D::new(s.foot_pos)
                .with_colors(s.contacts.map(|c| if c { green } else { grey }))
                .with_radii([0.025]),
        )?;
        let [px, py, pz] = trunk.translation;
        let command = rotate_out_of_frame(s.base_quat, [s.command[0], s.command[1], 0.0]);
        rec.log(
            "world/command",
            &::rerun::Arrows3D::from_vectors([[command[0], command[1], 0.0]])
                .with_origins([[px, py, pz + 0.1]])
                .with_colors([::rerun::Color::from_rgb(235, 195, 50)]),
        )?;
        rec.log(
            "world/velocity",
            &::rerun::Arrows3D::from_vectors([[s.base_lin_vel[0], s.base_lin_vel[1], 0.0]])
                .with_origins([[px, py, pz + 0.1]])
                .with_colors([::rerun::Color::from_rgb(70, 110, 200)]),
        )?;
        if let Some([dx, dy]) = s.push {
            rec.log(
                "world/push",
                &::rerun::Arrows3D::from_vectors([[dx, dy, 0.0]])
                    .with_origins([[px - dx, py - dy, pz]])
                    .with_colors([::rerun::Color::from_rgb(235, 80, 60)]),
            )?;
            self.push_until = Some(s.t + 0.5);
        } else if self.push_until.is_some_and(|until| s.t >= until) {
            rec.log("world/push", &::rerun::Clear::flat())?;
            self.push_until = None;
        }
        if let Some((reward, terms)) = s.reward {
            rec.log("reward/total", &::rerun::Scalars::single(f64::from(reward)))?;
            rec.log("reward/terms", &::rerun::Scalars::new(terms.map(f64::from)))?;
        }
        let [lin, ang] = s.tracking_errors();
        rec.log("tracking/lin_vel_err", &::rerun::Scalars::single(f64::from(lin)))?;
        rec.log("tracking/ang_vel_err", &::rerun::Scalars::single(f64::from(ang)))?;
        rec.log("joints/position", &::rerun::Scalars::new(s.q.map(f64::from)))?;
        rec.log("joints/torque", &::rerun::Scalars::new(s.torques.map(f64::from)))?;
        rec.log("command", &::rerun::Scalars::new(s.command.map(f64::from)))?;
        rec.log("base_velocity", &::rerun::Scalars::new(s.base_velocity().map(f64::from)))?;
        Ok(())
    }
}

impl SampleWriter for RerunWriter {
    fn record(&mut self, sample: &Sample) {
        if self.error.is_none() {
            if let Err(e) = self.log_step(sample) {
                self.error = Some(e.context(format!("logging the step at {:.2} s to Rerun", sample.t)));
            }
        }
    }

    fn finish(self) -> anyhow::Result<()> {
        let timeout = if self.live { Duration::from_secs(10) } else { Duration::MAX };
        let flushed = self.rec.flush_with_timeout(timeout);
        // Dropping the sinks ends the file sink's thread: the file's footer is written.
        self.rec.disconnect();
        if let Some(e) = self.error {
            if let Some((partial, _)) = &self.file {
                let _ = std::fs::remove_file(partial);
            }
            return Err(e);
        }
        match flushed {
            // A viewer closed before the end: the file, if any, is whole.
            Err(e) if self.live => tracing::warn!("the Rerun viewer did not take the whole recording: {e}"),
            Err(e) => anyhow::bail!("flushing the Rerun recording: {e}"),
            Ok(()) => {}
        }
        if let Some((partial, path)) = &self.file {
            std::fs::rename(partial, path)
                .with_context(|| format!("renaming {} to {}", partial.display(), path.display()))?;
        }
        Ok(())
    }
}
