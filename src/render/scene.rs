//! What a picture shows, taken from a `LocomotionEnv` after a step: every collider of the robot
//! and of the ground, with its world pose, its bounding box and its colour. The shapes are the
//! simulator's own (rapier's colliders: the URDF's collision geometry, meshes as the simulator
//! reads them), so a picture shows what the physics touches.

use crate::sim::{LocomotionEnv, Part};
use rapier3d::math::{Pose, Vector};
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::prelude::SharedShape;

/// A shape in the world.
#[derive(Clone)]
pub struct Body {
    pub shape: SharedShape,
    pub pose: Pose,
    pub aabb: Aabb,
    /// Linear RGB in [0, 1].
    pub colour: [f32; 3],
}

/// The robot and the ground at one instant.
#[derive(Clone)]
pub struct Scene {
    pub robot: Vec<Body>,
    /// The union of the robot's boxes: a ray that misses it misses the robot.
    pub robot_aabb: Aabb,
    pub ground: Vec<Body>,
    /// The height of the ground's top face when the ground is one unrotated box (flat ground):
    /// rays then meet it as a plane, the cheapest test of all (most pixels are ground).
    pub flat_ground: Option<f32>,
    /// The trunk's position (what the camera tracks).
    pub trunk: Vector,
}

/// The trunk's colour.
const TRUNK: [f32; 3] = [0.16, 0.19, 0.24];
/// A healthy leg's thigh and calf.
const LIMB: [f32; 3] = [0.62, 0.64, 0.68];
/// A leg the task perturbs (broken, inverted or noisy).
const PERTURBED: [f32; 3] = [0.85, 0.22, 0.14];
/// The feet.
const FOOT: [f32; 3] = [0.08, 0.08, 0.08];
/// The ground (its grid is drawn over it).
pub const GROUND: [f32; 3] = [0.80, 0.79, 0.75];

impl Scene {
    /// The scene of `env` as its last step left it; the legs its task perturbs drawn in red.
    pub fn of_env(env: &LocomotionEnv) -> Self {
        let perturbed: Vec<usize> = env.task().items().iter().map(|(_, leg)| leg.index()).collect();
        let shapes = env.collider_shapes();
        let (robot, ground) = (shapes.robot, shapes.ground);
        let colour = |part: Part| match part {
            Part::Trunk | Part::Other => TRUNK,
            Part::Foot(_) => FOOT,
            Part::Thigh(l) | Part::Calf(l) if perturbed.contains(&l) => PERTURBED,
            Part::Thigh(_) | Part::Calf(_) => LIMB,
        };
        let robot: Vec<Body> = robot.into_iter().map(|(shape, pose, part)| body(shape, pose, colour(part))).collect();
        let ground: Vec<Body> = ground.into_iter().map(|(shape, pose)| body(shape, pose, GROUND)).collect();
        let robot_aabb =
            robot.iter().skip(1).fold(robot.first().map_or(Aabb::new_invalid(), |b| b.aabb), |a, b| a.merged(&b.aabb));
        let trunk = Vector::from(env.raw_state().base_pos);
        let flat_ground = flat_top(&ground);
        Self { robot, robot_aabb, ground, flat_ground, trunk }
    }
}

fn body(shape: SharedShape, pose: Pose, colour: [f32; 3]) -> Body {
    let aabb = shape.compute_aabb(&pose);
    Body { shape, pose, aabb, colour }
}

/// The top face's height of a ground that is one unrotated box.
fn flat_top(ground: &[Body]) -> Option<f32> {
    let [only] = ground else { return None };
    let cuboid = only.shape.as_cuboid()?;
    only.pose.rotation.is_near_identity().then_some(only.pose.translation.z + cuboid.half_extents.z)
}
