//! Episodes as MCAP for Foxglove: JSON messages on JSON-schema channels,
//! zstd chunks, log time = simulation time (ns). One message per control
//! step on every channel but `/scene` (the link shapes, once, at time 0):
//!
//! | topic | schema | content |
//! | --- | --- | --- |
//! | `/tf` | `foxglove.FrameTransforms` | world to trunk and world to every leg link |
//! | `/scene` | `foxglove.SceneUpdate` | the URDF collision shapes, locked to their links |
//! | `/joint_states` | `quadcl.JointStates` | joint names, positions, velocities, efforts |
//! | `/command` | `quadcl.Command` | the velocity command |
//! | `/reward_terms` | `quadcl.RewardTerms` | the step reward and each term (METHOD Table 1) |
//! | `/contacts` | `quadcl.Contacts` | per foot: in contact, world position; a push |
//!
//! The simulation thread only copies each step (about 1 KB) into a bounded
//! channel; a writer thread encodes the JSON and compresses. The file is
//! written under a temporary name and renamed when the recording finishes,
//! so a file of that name is always a complete MCAP.

use super::foxglove::{self, FrameTransforms};
use super::recorder::{Recorder, SampleWriter};
use super::sample::Sample;
use crate::sim::{RobotModel, NUM_LEGS};
use anyhow::Context;
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// The topics, in the order their channels are made.
pub const TOPICS: [&str; 6] = ["/tf", "/scene", "/joint_states", "/command", "/reward_terms", "/contacts"];

const FEET: [&str; NUM_LEGS] = ["FL", "FR", "RL", "RR"];

/// The writing side, on its own thread.
struct McapWriter {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
    links: Vec<String>,
    joints: Vec<String>,
    path: PathBuf,
    partial: PathBuf,
    error: Option<anyhow::Error>,
    /// One message's JSON (reused).
    buffer: Vec<u8>,
}

#[derive(Serialize)]
struct JointStates<'a> {
    name: &'a [String],
    position: &'a [f32; 12],
    velocity: &'a [f32; 12],
    effort: &'a [f32; 12],
}

#[derive(Serialize)]
struct Command {
    vx: f32,
    vy: f32,
    wz: f32,
}

#[derive(Serialize)]
struct Foot {
    contact: bool,
    position: [f32; 3],
}

#[derive(Serialize)]
struct Contacts {
    feet: BTreeMap<&'static str, Foot>,
    push: Option<[f32; 2]>,
}

#[derive(Serialize)]
struct Rewards {
    reward: Option<f32>,
    terms: BTreeMap<&'static str, f32>,
    episode_step: usize,
}

impl Recorder {
    /// Records into the MCAP file `path` (written as `path.partial` until
    /// [`StepObserver::finish`](crate::sim::StepObserver::finish)) for `robot`.
    /// A file that cannot be created is an error now.
    pub fn mcap(path: &Path, robot: &RobotModel) -> anyhow::Result<Self> {
        Ok(Recorder::start(McapWriter::create(path, robot)?, "MCAP"))
    }
}

impl McapWriter {
    fn create(path: &Path, robot: &RobotModel) -> anyhow::Result<Self> {
        let partial = path.with_extension("mcap.partial");
        let file = File::create(&partial).with_context(|| format!("creating {}", partial.display()))?;
        let mut writer = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("")
            .create(BufWriter::new(file))
            .with_context(|| format!("starting the MCAP file {}", partial.display()))?;
        let arr = |t: &str| json!({"type": "array", "items": {"type": t}});
        let schemas: [(&str, Value); 6] = [
            ("foxglove.FrameTransforms", foxglove::frame_transforms_schema()),
            ("foxglove.SceneUpdate", foxglove::scene_update_schema()),
            (
                "quadcl.JointStates",
                foxglove::message_schema(
                    "quadcl.JointStates",
                    json!({"name": arr("string"), "position": arr("number"), "velocity": arr("number"), "effort": arr("number")}),
                ),
            ),
            (
                "quadcl.Command",
                foxglove::message_schema(
                    "quadcl.Command",
                    json!({"vx": {"type": "number"}, "vy": {"type": "number"}, "wz": {"type": "number"}}),
                ),
            ),
            (
                "quadcl.RewardTerms",
                foxglove::message_schema(
                    "quadcl.RewardTerms",
                    json!({"reward": {"type": ["number", "null"]}, "terms": {"type": "object"}, "episode_step": {"type": "integer"}}),
                ),
            ),
            (
                "quadcl.Contacts",
                foxglove::message_schema(
                    "quadcl.Contacts",
                    json!({"feet": {"type": "object"}, "push": {"type": ["array", "null"]}}),
                ),
            ),
        ];
        let mut channels = BTreeMap::new();
        for (topic, (name, schema)) in TOPICS.iter().zip(schemas) {
            let id = writer.add_schema(name, "jsonschema", schema.to_string().as_bytes())?;
            channels.insert(*topic, writer.add_channel(id, topic, "json", &BTreeMap::new())?);
        }
        let trunk = robot.urdf.links[robot.trunk_link].name.clone();
        let links: Vec<String> = std::iter::once(trunk)
            .chain(robot.joints.iter().map(|j| robot.urdf.links[j.child_link].name.clone()))
            .collect();
        let mut recorder = Self {
            writer: Some(writer),
            channels,
            sequence: 0,
            joints: robot.joints.iter().map(|j| j.name.clone()).collect(),
            path: path.to_path_buf(),
            partial,
            error: None,
            buffer: Vec::new(),
            links,
        };
        recorder.write("/scene", 0.0, &foxglove::scene(robot, &recorder.links));
        Ok(recorder)
    }

    fn write(&mut self, topic: &str, seconds: f64, message: &impl Serialize) {
        let (Some(w), None) = (self.writer.as_mut(), self.error.as_ref()) else { return };
        self.buffer.clear();
        if let Err(e) = serde_json::to_writer(&mut self.buffer, message) {
            self.error = Some(anyhow::Error::new(e).context(format!("encoding {topic}")));
            return;
        }
        let time = (seconds.max(0.0) * 1e9).round() as u64;
        let header = mcap::records::MessageHeader {
            channel_id: self.channels[topic],
            sequence: self.sequence,
            log_time: time,
            publish_time: time,
        };
        self.sequence += 1;
        if let Err(e) = w.write_to_known_channel(&header, &self.buffer) {
            self.error =
                Some(anyhow::Error::new(e).context(format!("writing {} to {}", topic, self.partial.display())));
        }
    }

    fn record_sample(&mut self, info: &Sample) {
        let t = info.t;
        let links = std::mem::take(&mut self.links);
        let transforms = links.iter().zip(&info.links).map(|(name, pose)| foxglove::transform(t, "world", name, pose));
        self.write("/tf", t, &FrameTransforms { transforms: transforms.collect() });
        self.links = links;
        let joints = std::mem::take(&mut self.joints);
        self.write(
            "/joint_states",
            t,
            &JointStates { name: &joints, position: &info.q, velocity: &info.qd, effort: &info.torques },
        );
        self.joints = joints;
        let [vx, vy, wz] = info.command;
        self.write("/command", t, &Command { vx, vy, wz });
        let terms = info
            .reward
            .map(|(_, values)| crate::sim::reward::TERM_NAMES.iter().copied().zip(values).collect::<BTreeMap<_, _>>());
        let rewards = Rewards {
            reward: info.reward.map(|(r, _)| r),
            terms: terms.unwrap_or_default(),
            episode_step: info.episode_step,
        };
        self.write("/reward_terms", t, &rewards);
        let feet = FEET
            .iter()
            .enumerate()
            .map(|(k, n)| (*n, Foot { contact: info.contacts[k], position: info.foot_pos[k] }))
            .collect();
        self.write("/contacts", t, &Contacts { feet, push: info.push });
    }
}

impl SampleWriter for McapWriter {
    fn record(&mut self, sample: &Sample) {
        self.record_sample(sample);
    }

    fn finish(mut self) -> anyhow::Result<()> {
        if let Some(e) = self.error.take() {
            let _ = std::fs::remove_file(&self.partial);
            return Err(e);
        }
        let Some(mut w) = self.writer.take() else { return Ok(()) };
        w.finish().with_context(|| format!("finishing {}", self.partial.display()))?;
        drop(w);
        std::fs::rename(&self.partial, &self.path)
            .with_context(|| format!("renaming {} to {}", self.partial.display(), self.path.display()))
    }
}
