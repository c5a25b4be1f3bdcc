//! The ground the robot walks on. Flat for now: a large thin box whose top
//! face is the plane z = 0 (a box, not a half-space, so its bounding box
//! stays finite for the broad phase).

use super::physics::GROUND_GROUP;
use rapier3d::prelude::*;

/// Half extent of the ground box in x and y, metres (the robot never walks 50 m in 20 s).
const HALF_EXTENT: f32 = 50.0;
/// Half thickness of the ground box, metres.
const HALF_THICKNESS: f32 = 0.5;

/// A flat ground collider at z = 0 with the given friction, seen only by robot colliders.
pub fn flat_ground(friction: f32) -> Collider {
    ColliderBuilder::cuboid(HALF_EXTENT, HALF_EXTENT, HALF_THICKNESS)
        .translation(Vector::new(0.0, 0.0, -HALF_THICKNESS))
        .friction(friction)
        .collision_groups(InteractionGroups::new(GROUND_GROUP, Group::ALL, InteractionTestMode::And))
        .build()
}
