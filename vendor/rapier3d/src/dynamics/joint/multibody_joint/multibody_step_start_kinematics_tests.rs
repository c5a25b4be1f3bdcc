//! `Multibody::set_step_start_kinematics(false)`: a step skips the forward-kinematics pass at
//! its start. Where the user moved nothing since the last step, that pass only recomputes the
//! poses and Jacobians the last step ended with, so skipping it must change nothing, bit for
//! bit, even with velocity changes between steps and contacts with the ground, and a change
//! rapier tracks (a teleported link, an appended one) must bring the pass back.

use crate::alloc_prelude::Vec;
use crate::prelude::*;

/// A floating three-link chain (free root, two hinges about non-parallel axes) with a ball on
/// each link, dropped from 0.6 m onto a fixed ground box.
fn falling_chain(step_start_kinematics: bool) -> (PhysicsWorld, MultibodyJointHandle, [RigidBodyHandle; 3]) {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 0.01;
    world.gravity = Vector::new(0.0, 0.0, -9.81);
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(
        ColliderBuilder::cuboid(5.0, 5.0, 0.1).translation(Vector::new(0.0, 0.0, -0.1)),
        Some(ground),
    );
    let mut links = [ground; 3];
    for (i, link) in links.iter_mut().enumerate() {
        *link = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.4 * i as Real, 0.0, 0.6))
                .can_sleep(false),
        );
        world.insert_collider(ColliderBuilder::ball(0.1).density(500.0), Some(*link));
    }
    let handle = world
        .insert_multibody_joint(
            links[0],
            links[1],
            RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0))
                .local_anchor1(Vector::new(0.2, 0.0, 0.0))
                .local_anchor2(Vector::new(-0.2, 0.0, 0.0)),
        )
        .unwrap();
    world
        .insert_multibody_joint(
            links[1],
            links[2],
            RevoluteJointBuilder::new(Vector::new(0.0, 1.0, 0.0))
                .local_anchor1(Vector::new(0.2, 0.0, 0.0))
                .local_anchor2(Vector::new(-0.2, 0.0, 0.0)),
        )
        .unwrap();
    let (multibody, _) = world.multibody_joints.get_mut(handle).unwrap();
    multibody.set_step_start_kinematics(step_start_kinematics);
    (world, handle, links)
}

/// Every link's pose and velocity, as bits.
fn state_bits(world: &PhysicsWorld, links: &[RigidBodyHandle; 3]) -> Vec<u32> {
    let mut bits = Vec::new();
    for h in links {
        let rb = &world.bodies[*h];
        let r = rb.rotation();
        for v in [rb.translation().x, rb.translation().y, rb.translation().z, r.x, r.y, r.z, r.w] {
            bits.push(v.to_bits());
        }
        for v in [rb.linvel().x, rb.linvel().y, rb.linvel().z, rb.angvel().x, rb.angvel().y, rb.angvel().z] {
            bits.push(v.to_bits());
        }
    }
    bits
}

#[test]
#[cfg(feature = "dim3")]
fn step_start_kinematics_is_on_by_default() {
    assert!(Multibody::new().step_start_kinematics());
    let (world, handle, _) = falling_chain(false);
    assert!(!world.multibody_joints.get(handle).unwrap().0.step_start_kinematics());
}

#[test]
#[cfg(feature = "dim3")]
fn skipping_step_start_kinematics_changes_nothing_when_nothing_moved() {
    let (mut with_pass, h_with, links_with) = falling_chain(true);
    let (mut without, h_without, links_without) = falling_chain(false);
    // Neither chain's root joint knows its body's pose yet: the first step must read it,
    // skipped pass or not.
    let mut touched = false;
    for step in 0..300 {
        // A velocity kick now and then, as a user's push would be.
        if step % 50 == 25 {
            for (world, handle) in [(&mut with_pass, h_with), (&mut without, h_without)] {
                let (multibody, _) = world.multibody_joints.get_mut(handle).unwrap();
                multibody.generalized_velocity_mut()[0] += 0.5;
                multibody.generalized_velocity_mut()[7] -= 2.0;
            }
        }
        with_pass.step();
        without.step();
        assert_eq!(
            state_bits(&with_pass, &links_with),
            state_bits(&without, &links_without),
            "the chains parted at step {step}"
        );
        touched |= with_pass.narrow_phase.contact_pairs().any(|p| p.has_any_active_contact());
    }
    assert!(touched, "the chain should land on the ground");
}

#[test]
#[cfg(feature = "dim3")]
fn a_teleported_link_is_followed_with_the_pass_off() {
    // Teleport the root's rigid-body 3 m up after the chain has taken a few steps: a tracked
    // change, so the next step runs the pass either way, and the chains stay bit for bit equal.
    let run = |step_start_kinematics: bool| -> (Real, Vec<u32>) {
        let (mut world, _, links) = falling_chain(step_start_kinematics);
        for _ in 0..5 {
            world.step();
        }
        let up = world.bodies[links[0]].translation() + Vector::new(0.0, 0.0, 3.0);
        world.bodies[links[0]].set_translation(up, true);
        world.step();
        let z = world.bodies[links[0]].translation().z;
        for _ in 0..20 {
            world.step();
        }
        (z, state_bits(&world, &links))
    };
    let (z_with, bits_with) = run(true);
    let (z_without, bits_without) = run(false);
    assert!(z_with > 3.0, "the default pass reads the moved root ({z_with})");
    assert!(z_without > 3.0, "the moved root is read with the pass off too ({z_without})");
    assert_eq!(bits_with, bits_without, "the chains parted after the teleport");
}

#[test]
#[cfg(feature = "dim3")]
fn links_appended_after_a_step_get_their_kinematics_with_the_pass_off() {
    // A fourth link joined to the chain after it has stepped: its poses and Jacobians do not
    // exist yet, so the next step must run the pass, switched off or not.
    let run = |step_start_kinematics: bool| -> Vec<u32> {
        let (mut world, _, links) = falling_chain(step_start_kinematics);
        for _ in 0..5 {
            world.step();
        }
        let tip = world.bodies[links[2]].translation() + Vector::new(0.4, 0.0, 0.0);
        let extra = world.insert_body(RigidBodyBuilder::dynamic().translation(tip).can_sleep(false));
        world.insert_collider(ColliderBuilder::ball(0.1).density(500.0), Some(extra));
        world
            .insert_multibody_joint(
                links[2],
                extra,
                RevoluteJointBuilder::new(Vector::new(0.0, 1.0, 0.0))
                    .local_anchor1(Vector::new(0.2, 0.0, 0.0))
                    .local_anchor2(Vector::new(-0.2, 0.0, 0.0)),
            )
            .unwrap();
        for _ in 0..50 {
            world.step();
        }
        let mut bits = state_bits(&world, &links);
        bits.push(world.bodies[extra].translation().z.to_bits());
        bits
    };
    assert_eq!(run(true), run(false), "the chains parted after a link was appended");
}
