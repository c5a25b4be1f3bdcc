//! The CPU renderer: one ray per pixel through the scene's colliders (parry's exact ray casts
//! against the simulator's own shapes, so boxes, cylinders, capsules, spheres and meshes alike),
//! Lambert shading under one sun with hard shadows cast by the robot, a ground grid (0.5 m
//! squares, 1 m lines), fog towards the horizon, and a sky gradient. No GPU, no system library.
//!
//! Cost: a ray first tests the ground and the robot's bounding box; only rays that enter the box
//! test the robot's colliders, each behind its own box. Rows are shared among rayon's threads
//! (one thread: `RAYON_NUM_THREADS=1` or a one-thread pool). Figures per frame are printed by
//! `quadcl bench --only render` (docs/recordings.md).

use super::camera::Camera;
use super::frame::{check_size, Frame};
use super::scene::{Body, Scene, GROUND};
use rapier3d::math::Vector;
use rapier3d::parry::query::{Ray, RayCast};
use rayon::prelude::*;

/// The farthest a ray looks, metres.
const FAR: f32 = 60.0;
/// Light that reaches a surface the sun does not (shadows, faces turned away).
const AMBIENT: f32 = 0.38;
/// Fog: the share of the sky's colour at distance d is 1 - exp(-d / FOG_DISTANCE).
const FOG_DISTANCE: f32 = 25.0;

/// The unit direction towards the sun: high, from the front left, so shadows fall behind right.
fn sun() -> Vector {
    Vector::new(0.35, 0.45, 1.0).normalize()
}

/// `scene` seen by `camera` as a `width` x `height` frame.
pub fn render(scene: &Scene, camera: &Camera, width: usize, height: usize) -> anyhow::Result<Frame> {
    check_size(width, height)?;
    let rays = camera.rays(scene.trunk, width, height);
    let mut rgb = vec![0u8; width * height * 3];
    rgb.par_chunks_mut(width * 3).enumerate().for_each(|(y, row)| {
        for x in 0..width {
            let c = shade(scene, &Ray::new(rays.eye, rays.direction(x, y)));
            row[3 * x..3 * x + 3].copy_from_slice(&to_srgb(c));
        }
    });
    Ok(Frame { width, height, rgb })
}

/// The closest hit along `ray` among `bodies` (behind `limit`): (distance, unit normal, body).
fn closest<'a>(bodies: &'a [Body], ray: &Ray, limit: f32) -> Option<(f32, Vector, &'a Body)> {
    let mut best: Option<(f32, Vector, &Body)> = None;
    for b in bodies {
        let max = best.map_or(limit, |(t, ..)| t);
        if b.aabb.cast_local_ray(ray, max, true).is_none() {
            continue;
        }
        if let Some(hit) = b.shape.cast_ray_and_get_normal(&b.pose, ray, max, true) {
            best = Some((hit.time_of_impact, hit.normal, b));
        }
    }
    best
}

/// The robot's closest hit along `ray` (behind `limit`), testing its bounding box first.
fn robot_hit<'a>(scene: &'a Scene, ray: &Ray, limit: f32) -> Option<(f32, Vector, &'a Body)> {
    scene.robot_aabb.cast_local_ray(ray, limit, true)?;
    closest(&scene.robot, ray, limit)
}

/// The linear colour seen along `ray`.
fn shade(scene: &Scene, ray: &Ray) -> [f32; 3] {
    let ground = match scene.flat_ground {
        Some(z) if ray.dir.z < 0.0 => Some(((z - ray.origin.z) / ray.dir.z, Vector::Z)).filter(|(t, _)| *t < FAR),
        Some(_) => None,
        None => closest(&scene.ground, ray, FAR).map(|(t, n, _)| (t, n)),
    };
    let robot = robot_hit(scene, ray, ground.map_or(FAR, |(t, _)| t));
    let sky = sky(ray.dir);
    let (t, normal, base) = match (robot, ground) {
        (Some((t, n, body)), _) => (t, n, body.colour),
        (None, Some((t, n))) => (t, n, grid(ray.point_at(t), t)),
        (None, None) => return sky,
    };
    let point = ray.point_at(t);
    // The normal towards the eye (a ray from inside a thin shape sees its back face).
    let normal = if normal.dot(ray.dir) > 0.0 { -normal } else { normal };
    let to_sun = sun();
    let facing = normal.dot(to_sun).max(0.0);
    let lit = if facing > 0.0 {
        let shadow_ray = Ray::new(point + normal * 1e-3, to_sun);
        if robot_hit(scene, &shadow_ray, 5.0).is_some() {
            0.0
        } else {
            facing
        }
    } else {
        0.0
    };
    let light = AMBIENT + (1.0 - AMBIENT) * lit;
    let fog = 1.0 - (-t / FOG_DISTANCE).exp();
    std::array::from_fn(|i| base[i] * light * (1.0 - fog) + sky[i] * fog)
}

/// Beyond this distance, metres, the ground's pattern has faded out (one ray a pixel would
/// alias it into noise there).
const GRID_FADE: f32 = 10.0;

/// The ground's colour at `point`, seen from `distance`: light and dark 0.5 m squares with
/// darker 1 m lines, fading to plain ground with distance.
fn grid(point: Vector, distance: f32) -> [f32; 3] {
    let (x, y) = (point.x, point.y);
    let line = |v: f32| {
        let f = v - v.round();
        f.abs() < 0.008
    };
    let k = if line(x) || line(y) {
        0.56
    } else if ((x * 2.0).floor() as i64 + (y * 2.0).floor() as i64).rem_euclid(2) == 0 {
        1.0
    } else {
        0.92
    };
    let fade = (1.0 - distance / GRID_FADE).clamp(0.0, 1.0);
    GROUND.map(|c| c * (1.0 - (1.0 - k) * fade))
}

/// The sky's colour in direction `dir`: pale at the horizon, deeper blue overhead.
fn sky(dir: Vector) -> [f32; 3] {
    let up = dir.z.clamp(0.0, 1.0);
    let (horizon, zenith) = ([0.78, 0.84, 0.90], [0.33, 0.50, 0.75]);
    std::array::from_fn(|i| horizon[i] + (zenith[i] - horizon[i]) * up)
}

/// Levels of the linear-to-sRGB table (finer than a byte's steps in the darks).
const SRGB_LEVELS: usize = 4096;

/// Linear [0, 1] to sRGB bytes, through a table (a `powf` per channel was a fifth of a frame).
fn to_srgb(c: [f32; 3]) -> [u8; 3] {
    static TABLE: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=SRGB_LEVELS)
            .map(|i| {
                let v = i as f32 / SRGB_LEVELS as f32;
                let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
                (s * 255.0 + 0.5) as u8
            })
            .collect()
    });
    c.map(|v| table[(v.clamp(0.0, 1.0) * SRGB_LEVELS as f32 + 0.5) as usize])
}
