//! Foxglove's message shapes as JSON (the subset quadcl writes), their JSON
//! schemas, and the robot's link shapes (URDF collision boxes, cylinders,
//! capsules and spheres) as one `foxglove.SceneUpdate`.

use crate::sim::{LinkPose, RobotModel};
use rapier3d_urdf::urdf_rs::Geometry;
use serde::Serialize;
use serde_json::{json, Value};

/// Nanoseconds of `seconds` as Foxglove's `{sec, nsec}`.
pub fn time(seconds: f64) -> Value {
    let ns = (seconds.max(0.0) * 1e9).round() as u64;
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

/// Foxglove's `{sec, nsec}`.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Time {
    pub sec: u64,
    pub nsec: u64,
}

impl Time {
    pub fn of(seconds: f64) -> Self {
        let ns = (seconds.max(0.0) * 1e9).round() as u64;
        Self { sec: ns / 1_000_000_000, nsec: ns % 1_000_000_000 }
    }
}

#[derive(Debug, Clone, Copy, Serialize)]
pub struct Vector3 {
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

#[derive(Debug, Clone, Copy, Serialize)]
pub struct Quaternion {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    pub w: f32,
}

/// A `foxglove.FrameTransform`.
#[derive(Debug, Clone, Serialize)]
pub struct FrameTransform<'a> {
    pub timestamp: Time,
    pub parent_frame_id: &'a str,
    pub child_frame_id: &'a str,
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// A `foxglove.FrameTransforms`.
#[derive(Debug, Clone, Serialize)]
pub struct FrameTransforms<'a> {
    pub transforms: Vec<FrameTransform<'a>>,
}

/// A `foxglove.FrameTransform` from `parent` to `child`.
pub fn transform<'a>(seconds: f64, parent: &'a str, child: &'a str, pose: &LinkPose) -> FrameTransform<'a> {
    let [x, y, z] = pose.translation;
    let [qx, qy, qz, qw] = pose.rotation;
    FrameTransform {
        timestamp: Time::of(seconds),
        parent_frame_id: parent,
        child_frame_id: child,
        translation: Vector3 { x, y, z },
        rotation: Quaternion { x: qx, y: qy, z: qz, w: qw },
    }
}

/// Quaternion (x, y, z, w) of URDF roll-pitch-yaw (fixed axes x, then y, then z).
fn quat_from_rpy(rpy: [f64; 3]) -> [f64; 4] {
    let (hr, hp, hy) = (rpy[0] / 2.0, rpy[1] / 2.0, rpy[2] / 2.0);
    let (sr, cr, sp, cp, sy, cy) = (hr.sin(), hr.cos(), hp.sin(), hp.cos(), hy.sin(), hy.cos());
    [sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy]
}

/// The link shapes of `robot` (its collision geometry), one entity per link, locked to the
/// link's frame: a `foxglove.SceneUpdate`. `links` names the frames (trunk first).
pub fn scene(robot: &RobotModel, links: &[String]) -> Value {
    let color = |k: usize| {
        if k == 0 {
            json!({"r": 0.75, "g": 0.75, "b": 0.8, "a": 1.0})
        } else {
            json!({"r": 0.25, "g": 0.45, "b": 0.85, "a": 1.0})
        }
    };
    let mut entities = Vec::new();
    for (k, name) in links.iter().enumerate() {
        let Some(link) = robot.urdf.links.iter().find(|l| &l.name == name) else { continue };
        let (mut cubes, mut cylinders, mut spheres) = (Vec::new(), Vec::new(), Vec::new());
        for c in &link.collision {
            let (p, q) = (c.origin.xyz.0, quat_from_rpy(c.origin.rpy.0));
            let pose = json!({
                "position": {"x": p[0], "y": p[1], "z": p[2]},
                "orientation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]},
            });
            match &c.geometry {
                Geometry::Box { size } => cubes.push(
                    json!({"pose": pose, "size": {"x": size.0[0], "y": size.0[1], "z": size.0[2]}, "color": color(k)}),
                ),
                Geometry::Cylinder { radius, length } => cylinders.push(json!({
                    "pose": pose, "size": {"x": 2.0 * radius, "y": 2.0 * radius, "z": length},
                    "bottom_scale": 1.0, "top_scale": 1.0, "color": color(k),
                })),
                // Foxglove has no capsule: a cylinder as long as the capsule, ends included.
                Geometry::Capsule { radius, length } => cylinders.push(json!({
                    "pose": pose, "size": {"x": 2.0 * radius, "y": 2.0 * radius, "z": length + 2.0 * radius},
                    "bottom_scale": 1.0, "top_scale": 1.0, "color": color(k),
                })),
                Geometry::Sphere { radius } => spheres.push(json!({
                    "pose": pose, "size": {"x": 2.0 * radius, "y": 2.0 * radius, "z": 2.0 * radius},
                    "color": json!({"r": 0.1, "g": 0.1, "b": 0.1, "a": 1.0}),
                })),
                _ => {}
            }
        }
        entities.push(json!({
            "timestamp": time(0.0), "frame_id": name, "id": name, "lifetime": {"sec": 0, "nsec": 0},
            "frame_locked": true, "metadata": [], "arrows": [], "cubes": cubes, "spheres": spheres,
            "cylinders": cylinders, "lines": [], "triangles": [], "texts": [], "models": [],
        }));
    }
    json!({"deletions": [], "entities": entities})
}

fn object(properties: Value, required: &[&str]) -> Value {
    json!({"type": "object", "properties": properties, "required": required})
}

/// The JSON schema of a message named `title` with `properties`, none required.
pub fn message_schema(title: &str, properties: Value) -> Value {
    let mut s = object(properties, &[]);
    s["title"] = json!(title);
    s
}

fn number() -> Value {
    json!({"type": "number"})
}

fn vec3() -> Value {
    object(json!({"x": number(), "y": number(), "z": number()}), &["x", "y", "z"])
}

fn quat() -> Value {
    object(json!({"x": number(), "y": number(), "z": number(), "w": number()}), &["x", "y", "z", "w"])
}

fn timestamp() -> Value {
    object(json!({"sec": {"type": "integer"}, "nsec": {"type": "integer"}}), &["sec", "nsec"])
}

/// JSON schema of `foxglove.FrameTransforms`.
pub fn frame_transforms_schema() -> Value {
    let t = object(
        json!({"timestamp": timestamp(), "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
               "translation": vec3(), "rotation": quat()}),
        &["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"],
    );
    let mut s = message_schema("foxglove.FrameTransforms", json!({"transforms": {"type": "array", "items": t}}));
    s["required"] = json!(["transforms"]);
    s
}

/// JSON schema of `foxglove.SceneUpdate` (the primitives quadcl writes; the rest as arrays).
pub fn scene_update_schema() -> Value {
    let pose = object(json!({"position": vec3(), "orientation": quat()}), &["position", "orientation"]);
    let color = object(json!({"r": number(), "g": number(), "b": number(), "a": number()}), &["r", "g", "b", "a"]);
    let shape = object(json!({"pose": pose, "size": vec3(), "color": color}), &["pose", "size", "color"]);
    let any = json!({"type": "array"});
    let entity = object(
        json!({"timestamp": timestamp(), "frame_id": {"type": "string"}, "id": {"type": "string"},
               "lifetime": timestamp(), "frame_locked": {"type": "boolean"}, "metadata": any,
               "arrows": any, "cubes": {"type": "array", "items": shape}, "spheres": {"type": "array", "items": shape},
               "cylinders": {"type": "array", "items": shape}, "lines": any, "triangles": any, "texts": any,
               "models": any}),
        &["timestamp", "frame_id", "id", "lifetime", "frame_locked"],
    );
    let mut s = message_schema(
        "foxglove.SceneUpdate",
        json!({"deletions": any, "entities": {"type": "array", "items": entity}}),
    );
    s["required"] = json!(["entities"]);
    s
}
