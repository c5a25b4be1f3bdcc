//! `Multibody::set_implicit_coriolis(false)`: the velocity-product forces (Coriolis,
//! centrifugal, gyroscopic) computed explicitly and the free accelerations solved against the
//! plain mass matrix, as MuJoCo's `implicitfast` integrator treats them.
//!
//! The two treatments differ by O(dt) per step, so at a small step they must follow the same
//! trajectory, and at a large one the explicit mode must still conserve a free double
//! pendulum's energy roughly (no blow-up). A double pendulum swinging about two non-parallel
//! hinges has strong Coriolis and centrifugal couplings, which is what the mode changes.

use crate::prelude::*;

/// A double pendulum on a fixed root, released from a bent pose: hinge 1 about z, hinge 2
/// about y (so the second link's swing couples through Coriolis terms), no damping.
fn double_pendulum(implicit: bool, dt: Real) -> (PhysicsWorld, [RigidBodyHandle; 2]) {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = dt;
    let root = world.insert_body(RigidBodyBuilder::fixed());
    let link1 = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(1.0, 0.0, 0.0))
            .additional_mass_properties(MassProperties::new(
                Vector::ZERO,
                1.0,
                Vector::new(0.01, 0.05, 0.05),
            ))
            .can_sleep(false),
    );
    let link2 = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.0, 0.0, 0.0))
            .additional_mass_properties(MassProperties::new(
                Vector::ZERO,
                1.0,
                Vector::new(0.01, 0.05, 0.05),
            ))
            .can_sleep(false),
    );
    let joint1 = world
        .insert_multibody_joint(
            root,
            link1,
            RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0))
                .local_anchor1(Vector::ZERO)
                .local_anchor2(Vector::new(-1.0, 0.0, 0.0)),
        )
        .unwrap();
    world
        .insert_multibody_joint(
            link1,
            link2,
            RevoluteJointBuilder::new(Vector::new(0.0, 1.0, 0.0))
                .local_anchor1(Vector::new(0.5, 0.0, 0.0))
                .local_anchor2(Vector::new(-0.5, 0.0, 0.0)),
        )
        .unwrap();
    let (multibody, _) = world.multibody_joints.get_mut(joint1).unwrap();
    multibody.set_implicit_coriolis(implicit);
    // Gravity along -y swings hinge 1; a start speed on hinge 2 couples the two.
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    let last = multibody.ndofs() - 1;
    multibody.generalized_velocity_mut()[last] = 4.0;
    (world, [link1, link2])
}

/// Kinetic plus potential energy of the two links (unit masses, gravity along -y).
fn energy(world: &PhysicsWorld, links: [RigidBodyHandle; 2]) -> Real {
    links
        .iter()
        .map(|h| {
            let rb = &world.bodies[*h];
            let inertia = rb
                .mass_properties()
                .local_mprops
                .reconstruct_inertia_matrix();
            let w_local = rb.rotation().inverse() * rb.angvel();
            0.5 * rb.mass() * rb.linvel().length_squared()
                + 0.5 * w_local.dot(inertia * w_local)
                + rb.mass() * 9.81 * rb.center_of_mass().y
        })
        .sum()
}

#[test]
#[cfg(feature = "dim3")]
fn implicit_coriolis_stays_rapiers_default_and_is_switchable() {
    let (world, _) = double_pendulum(false, 1.0 / 60.0);
    let multibody = world.multibody_joints.multibodies().next().unwrap();
    assert!(!multibody.implicit_coriolis());
    assert!(
        Multibody::new().implicit_coriolis(),
        "rapier's default stays semi-implicit"
    );
}

#[test]
#[cfg(feature = "dim3")]
fn explicit_and_implicit_coriolis_follow_the_same_trajectory_at_a_small_step() {
    let dt = 1.0 / 2000.0;
    let (mut implicit, links_i) = double_pendulum(true, dt);
    let (mut explicit, links_e) = double_pendulum(false, dt);
    let mut largest_gap: Real = 0.0;
    for _ in 0..2000 {
        implicit.step();
        explicit.step();
        let gap = (implicit.bodies[links_i[1]].translation()
            - explicit.bodies[links_e[1]].translation())
        .length();
        largest_gap = largest_gap.max(gap);
    }
    // The tip moved by metres over the second; the two treatments agree to millimetres.
    let travel = (explicit.bodies[links_e[1]].translation() - Vector::new(2.0, 0.0, 0.0)).length();
    assert!(travel > 0.5, "the pendulum should swing: {travel}");
    assert!(largest_gap < 5.0e-3, "trajectories part by {largest_gap} m");
}

#[test]
#[cfg(feature = "dim3")]
fn explicit_coriolis_keeps_a_free_double_pendulum_bounded_at_a_large_step() {
    let (mut world, links) = double_pendulum(false, 1.0 / 100.0);
    world.step();
    let start = energy(&world, links);
    let mut highest = start;
    for _ in 0..500 {
        world.step();
        let e = energy(&world, links);
        assert!(e.is_finite(), "energy became {e}");
        highest = highest.max(e);
    }
    // Undamped and torque-free but for gravity: the energy may wander with the integrator's
    // error, but must not grow without bound.
    let scale = start.abs().max(1.0);
    assert!(
        highest - start < 0.25 * scale,
        "energy grew from {start} to {highest} J"
    );
}
