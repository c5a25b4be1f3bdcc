//! One robot in one rapier world: the URDF turned into a multibody
//! (reduced coordinates) by rapier3d-urdf, PD motors on the 12 leg joints,
//! and the state read back in the quantities the environment needs.
//!
//! rapier3d-urdf ignores effort limits and resets joints to zero, so the
//! standing pose is applied after insertion, and the PD law (Kp, Kd in
//! N m / rad, times the episode's motor strength, clamped to each joint's
//! effort limit) is applied here as rapier's implicit joint spring and
//! damping rather than as solver motors (see [`RobotSim::step`]). Only
//! robot-ground contacts exist: robot colliders are in group 1 and see only
//! group 2 (the ground), and self contacts are disabled. Bodies never sleep
//! (determinism).

use super::robot::{Leg, RobotModel, NUM_LEGS};
use super::terrain;
use crate::config::{CoriolisForces, EnvConfig};
use rapier3d::math::{Pose, Vector};
use rapier3d::prelude::*;
use rapier3d_urdf::{UrdfLoaderOptions, UrdfMultibodyOptions, UrdfRobot};

/// Stiffness of the speculative joint stop, N m / rad: dt^2 * k (1 at 0.01 s)
/// dwarfs any leg's inertia about its joint (< 0.1 kg m^2), so the joint stops
/// at the limit within the step.
const LIMIT_STIFFNESS: f32 = 1.0e4;

/// Group of robot colliders.
const ROBOT_GROUP: Group = Group::GROUP_1;
/// Group of ground colliders.
pub const GROUND_GROUP: Group = Group::GROUP_2;

/// What a robot collider is, for contact bookkeeping.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Trunk,
    Thigh(usize),
    Calf(usize),
    Foot(usize),
    Other,
}

/// Per-episode physical parameters (domain randomisation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhysicsParams {
    /// Friction coefficient of every robot and ground collider.
    pub friction: f32,
    /// Mass added to the trunk, kg.
    pub added_mass: f32,
    /// Factor on motor gains and effort limits.
    pub motor_strength: f32,
}

/// PD gains per leg joint, in leg-joint order (before the episode's motor strength).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PdGains {
    /// Stiffness, N m / rad.
    pub kp: [f32; 12],
    /// Damping, N m s / rad.
    pub kd: [f32; 12],
}

/// The robot's state after a physics step, in world frame unless named.
#[derive(Debug, Clone, Copy, Default)]
pub struct RawState {
    pub base_pos: [f32; 3],
    /// Trunk orientation quaternion (x, y, z, w).
    pub base_quat: [f32; 4],
    pub base_lin_vel: [f32; 3],
    pub base_ang_vel: [f32; 3],
    pub q: [f32; 12],
    pub qd: [f32; 12],
    pub foot_pos: [[f32; 3]; NUM_LEGS],
}

/// The world's colliders with their world poses (shapes are shared, not copied).
pub struct WorldShapes {
    /// Each robot collider's shape, pose and part.
    pub robot: Vec<(SharedShape, Pose, Part)>,
    /// The ground's colliders.
    pub ground: Vec<(SharedShape, Pose)>,
}

/// One robot in its own world.
pub struct RobotSim {
    world: PhysicsWorld,
    multibody: MultibodyIndex,
    /// Multibody link id of each leg joint's child link, in leg-joint order.
    joint_links: [usize; 12],
    /// Multibody link id of each leg's calf.
    calf_links: [usize; NUM_LEGS],
    foot_offsets: [[f32; 3]; NUM_LEGS],
    effort: [f32; 12],
    /// (lower, upper) position limit of each leg joint, rad.
    limits: [[f32; 2]; 12],
    /// Whether rapier3d-urdf gave each leg joint a rapier limit (its angular axis in
    /// `limit_axes`): [`Self::step`] switches that axis on only while the joint is past it.
    rapier_limits: [bool; 12],
    /// (collider, part) of every robot collider.
    parts: Vec<(ColliderHandle, Part)>,
    ground: ColliderHandle,
    gains: PdGains,
    strength: f32,
    /// Current PD position targets, rad.
    targets: [f32; 12],
    /// PD torques (clamped) at the start of the last physics step, N m.
    last_torques: [f32; 12],
}

impl RobotSim {
    /// Builds the world: ground, robot at `cfg.start_height` in pose `q0`
    /// (12 joint angles), at rest; step and solver from `cfg`.
    pub fn new(
        robot: &RobotModel,
        cfg: &EnvConfig,
        params: PhysicsParams,
        q0: &[f32; 12],
        gains: &PdGains,
    ) -> anyhow::Result<Self> {
        let (dt, solver_iterations, height) = (cfg.physics_dt, cfg.solver_iterations, cfg.start_height);
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -9.81);
        let ip = &mut world.integration_parameters;
        ip.dt = dt;
        ip.num_solver_iterations = solver_iterations;
        ip.max_ccd_substeps = 0;

        let ground = world.colliders.insert(terrain::flat_ground(params.friction));

        let mut urdf = robot.urdf.clone();
        urdf.links[robot.trunk_link].inertial.mass.value += params.added_mass as f64;
        let trunk_mass = urdf.links[robot.trunk_link].inertial.mass.value;
        anyhow::ensure!(
            trunk_mass > 0.0,
            "{}: trunk mass {trunk_mass} kg after adding {} kg (env.added_mass_range) must be > 0",
            robot.path.display(),
            params.added_mass
        );
        let options = UrdfLoaderOptions {
            collider_blueprint: ColliderBuilder::default()
                .density(0.0)
                .friction(params.friction)
                .collision_groups(InteractionGroups::new(ROBOT_GROUP, GROUND_GROUP, InteractionTestMode::And)),
            rigid_body_blueprint: RigidBodyBuilder::dynamic().can_sleep(false),
            shift: Pose::from_translation(Vector::new(0.0, 0.0, height)),
            ..Default::default()
        };
        let mesh_dir = robot.path.parent().unwrap_or(std::path::Path::new("."));
        let rapier_robot = UrdfRobot::from_robot(&urdf, options, mesh_dir);
        let link_sources: Vec<usize> = rapier_robot.links.iter().map(|l| l.urdf_link_index).collect();
        let joint_sources: Vec<usize> = rapier_robot.joints.iter().map(|j| j.urdf_joint_index).collect();
        let handles = rapier_robot.insert_using_multibody_joints(
            &mut world.bodies,
            &mut world.colliders,
            &mut world.multibody_joints,
            UrdfMultibodyOptions::DISABLE_SELF_CONTACTS,
        );

        let mut joint_links = [0usize; 12];
        let mut multibody = None;
        for (i, leg_joint) in robot.joints.iter().enumerate() {
            let k = joint_sources.iter().position(|&s| s == leg_joint.urdf_joint).ok_or_else(|| {
                anyhow::anyhow!("{}: joint '{}' was not built by the loader", robot.path.display(), leg_joint.name)
            })?;
            let body = handles.joints[k].link2;
            let link = world.multibody_joints.rigid_body_link(body).ok_or_else(|| {
                anyhow::anyhow!("{}: joint '{}' is not part of the multibody", robot.path.display(), leg_joint.name)
            })?;
            multibody = Some(link.multibody);
            joint_links[i] = link.id;
        }
        let multibody = multibody.expect("12 leg joints");
        world
            .multibody_joints
            .get_multibody_mut(multibody)
            .expect("robot multibody exists")
            .set_implicit_coriolis(cfg.coriolis == CoriolisForces::Implicit);
        let calf_links = [joint_links[2], joint_links[5], joint_links[8], joint_links[11]];

        // Classify colliders by the URDF link they belong to.
        let mut parts = Vec::new();
        for (k, link_handle) in handles.links.iter().enumerate() {
            let urdf_link = link_sources[k];
            let part_of = |c: usize| -> Part {
                if urdf_link == robot.trunk_link {
                    return Part::Trunk;
                }
                for leg in Leg::ALL {
                    let l = leg.index();
                    if robot.joints[3 * l + 1].child_link == urdf_link {
                        return Part::Thigh(l);
                    }
                    if robot.joints[3 * l + 2].child_link == urdf_link {
                        return if robot.foot_collisions[l].contains(&c) { Part::Foot(l) } else { Part::Calf(l) };
                    }
                }
                Part::Other
            };
            // One collider per URDF collision shape, in order (meshes are primitives by now).
            for (i, c) in link_handle.colliders.iter().enumerate() {
                parts.push((c.handle, part_of(i)));
            }
        }

        let effort: [f32; 12] = std::array::from_fn(|i| robot.joints[i].effort);
        let limits: [[f32; 2]; 12] = std::array::from_fn(|i| [robot.joints[i].lower, robot.joints[i].upper]);
        let mb = &world.multibody_joints[multibody];
        let rapier_limits = joint_links.map(|id| {
            let joint = &mb.link(id).expect("leg link exists").joint;
            joint.data.limit_axes.contains(JointAxesMask::ANG_X)
        });
        let mut sim = Self {
            world,
            multibody,
            joint_links,
            calf_links,
            foot_offsets: robot.foot_offsets,
            effort,
            limits,
            rapier_limits,
            parts,
            ground,
            gains: *gains,
            strength: params.motor_strength,
            targets: *q0,
            last_torques: [0.0; 12],
        };
        sim.init_gains();
        sim.set_pose(height, q0);
        Ok(sim)
    }

    fn mb(&self) -> &Multibody {
        &self.world.multibody_joints[self.multibody]
    }

    fn mb_mut(&mut self) -> &mut Multibody {
        self.world.multibody_joints.get_multibody_mut(self.multibody).expect("robot multibody exists")
    }

    /// Joint damping: Kd on the leg joints (implicit), none on the free root
    /// (rapier gives every angular dof a default damping of 0.1); springs Kp.
    fn init_gains(&mut self) {
        let kp = self.gains.kp.map(|k| k * self.strength);
        let kd = self.gains.kd.map(|k| k * self.strength);
        let links = self.joint_links;
        let targets = self.targets;
        let mb = self.world.multibody_joints.get_multibody_mut(self.multibody).expect("robot multibody exists");
        mb.damping_mut().fill(0.0);
        for (i, &id) in links.iter().enumerate() {
            let assembly = mb.link(id).expect("leg link exists").assembly_id();
            mb.damping_mut()[assembly] = kd[i];
            mb.link_mut(id).expect("leg link exists").joint.set_spring(3, kp[i], targets[i]);
        }
    }

    /// Puts the trunk at `height` (upright, at the origin) and the joints at
    /// `q0`, then updates the bodies. rapier starts a multibody's free root
    /// joint at the identity pose whatever its body's pose, and every joint at 0.
    fn set_pose(&mut self, height: f32, q0: &[f32; 12]) {
        let links = self.joint_links;
        let mb = self.world.multibody_joints.get_multibody_mut(self.multibody).expect("robot multibody exists");
        let root = mb.root_mut();
        let c = root.joint.coords();
        root.joint.apply_displacement(&[-c[0], -c[1], height - c[2], 0.0, 0.0, 0.0]);
        for (i, &id) in links.iter().enumerate() {
            let link = mb.link_mut(id).expect("leg link exists");
            let current = link.joint.coords()[3];
            link.joint.apply_displacement(&[q0[i] - current]);
        }
        mb.forward_kinematics(&self.world.bodies, false);
        mb.update_rigid_bodies(&mut self.world.bodies, true);
        // Nothing moves the robot between steps from here on (a reset builds a new world;
        // pushes change velocities only), so the step-start kinematics pass would recompute
        // the last step's poses and Jacobians bit for bit (vendor/rapier3d/PATCH.md, item 7).
        mb.set_step_start_kinematics(false);
    }

    /// Sets the 12 PD position targets (rad) for the following physics steps.
    pub fn set_targets(&mut self, targets: &[f32; 12]) {
        self.targets = *targets;
    }

    /// The current PD targets, rad.
    pub fn targets(&self) -> &[f32; 12] {
        &self.targets
    }

    /// The PD torques (clamped to the effort limits) at the start of the last physics step, N m.
    pub fn last_torques(&self) -> &[f32; 12] {
        &self.last_torques
    }

    /// Advances the world by one physics step. The PD law acts inside
    /// rapier's generalised dynamics: stiffness Kp as an implicit joint spring,
    /// Kd as implicit joint damping (both stable at any step). Where the PD
    /// torque at the step's start would exceed the effort limit, the spring's
    /// rest point is moved so that it asks for exactly the limit.
    ///
    /// Joint limits are made speculative the same way: rapier's own limit
    /// constraint only acts once a joint is past its limit, so a fast joint
    /// overshoots by up to velocity * dt (0.1 rad at 0.01 s). A joint that
    /// would cross a limit within this step instead gets, for this step, a
    /// very stiff implicit spring resting on the limit: a mechanical stop.
    pub fn step(&mut self) -> anyhow::Result<()> {
        let kp = self.gains.kp.map(|k| k * self.strength);
        let kd = self.gains.kd.map(|k| k * self.strength);
        let dt = self.world.integration_parameters.dt;
        let links = self.joint_links;
        let targets = self.targets;
        let limits = self.limits;
        let effort = self.effort.map(|e| e * self.strength);
        let rapier_limits = self.rapier_limits;
        let mb = self.world.multibody_joints.get_multibody_mut(self.multibody).expect("robot multibody exists");
        for (i, &id) in links.iter().enumerate() {
            let link = mb.link(id).expect("leg link exists");
            let q = link.joint.coords()[3];
            let qd = mb.joint_velocity(link)[0];
            let (kp, kd) = (kp[i], kd[i]);
            let tau = kp * (targets[i] - q) - kd * qd;
            self.last_torques[i] = tau.clamp(-effort[i], effort[i]);
            let predicted = q + qd * dt;
            let (stiffness, rest) = if predicted > limits[i][1] {
                (LIMIT_STIFFNESS, limits[i][1])
            } else if predicted < limits[i][0] {
                (LIMIT_STIFFNESS, limits[i][0])
            } else if tau.abs() <= effort[i] {
                (kp, targets[i])
            } else {
                (kp, q + (effort[i].copysign(tau) + kd * qd) / kp)
            };
            let joint = &mut mb.link_mut(id).expect("leg link exists").joint;
            joint.set_spring(3, stiffness, rest);
            // rapier builds a limit row (one solve against the 18 x 18 mass matrix, and a
            // row in every solver pass) for every limited axis each step, but a row whose
            // joint is within its limits has impulse bounds [-0, 0]: it never acts. So the
            // axis is limited only while the joint is past a limit, by rapier's own test
            // (`unit_joint_limit_constraint`) on its own stored limits: the same dynamics.
            if rapier_limits[i] {
                let stored = joint.data.limits[3];
                let past = q < stored.min || stored.max < q;
                joint.data.limit_axes.set(JointAxesMask::ANG_X, past);
            }
        }
        // rapier may panic on non-finite state (e.g. a NaN bounding box); turn that
        // into an error the env reports with its context.
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.world.step())).map_err(|payload| {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            anyhow::Error::new(super::episode::PhysicsBlowUp(format!("rapier failed inside a physics step: {what}")))
        })
    }

    /// Reads the robot state.
    pub fn state(&self) -> RawState {
        let mb = self.mb();
        let root = mb.root().local_to_world();
        let vel = mb.generalized_velocity();
        let mut s = RawState {
            base_pos: root.translation.into(),
            base_quat: root.rotation.into(),
            base_lin_vel: [vel[0], vel[1], vel[2]],
            base_ang_vel: [vel[3], vel[4], vel[5]],
            ..Default::default()
        };
        for (i, &id) in self.joint_links.iter().enumerate() {
            let link = mb.link(id).expect("leg link exists");
            s.q[i] = link.joint.coords()[3];
            s.qd[i] = mb.joint_velocity(link)[0];
        }
        for l in 0..NUM_LEGS {
            let pose = mb.link(self.calf_links[l]).expect("calf link exists").local_to_world();
            s.foot_pos[l] = (pose * Vector::from(self.foot_offsets[l])).into();
        }
        s
    }

    /// World position of each leg joint (its child link's origin), in leg-joint order (`sim::pose`).
    /// World poses of the trunk and of each leg joint's child link (translation, quaternion x y z w).
    pub fn link_poses(&self) -> [super::observe::LinkPose; 13] {
        std::array::from_fn(|k| {
            let id = if k == 0 { 0 } else { self.joint_links[k - 1] };
            let pose = self.mb().link(id).expect("link exists").local_to_world();
            let (t, r) = (pose.translation, pose.rotation);
            super::observe::LinkPose { translation: t.into(), rotation: [r.x, r.y, r.z, r.w] }
        })
    }

    pub fn joint_positions(&self) -> [[f32; 3]; 12] {
        self.joint_links.map(|id| self.mb().link(id).expect("leg link exists").local_to_world().translation.into())
    }

    /// Every robot collider and the ground's as the last physics step left them: what a
    /// picture of the world draws (`render::Scene`).
    pub fn collider_shapes(&self) -> WorldShapes {
        let shape = |c: ColliderHandle| {
            let c = &self.world.colliders[c];
            (c.shared_shape().clone(), *c.position())
        };
        let robot = self
            .parts
            .iter()
            .map(|&(c, part)| {
                let (shape, pose) = shape(c);
                (shape, pose, part)
            })
            .collect();
        WorldShapes { robot, ground: vec![shape(self.ground)] }
    }

    /// Adds `dv` (world x, y) to the trunk's linear velocity (a push).
    pub fn push(&mut self, dv: [f32; 2]) {
        let mut vel = self.mb_mut().generalized_velocity_mut();
        vel[0] += dv[0];
        vel[1] += dv[1];
    }

    /// Whether a part of this kind touches the ground (see [`touches`]): returns (trunk, per-leg thigh/calf count, per-leg foot).
    pub fn contacts(&self) -> (bool, [u32; NUM_LEGS], [bool; NUM_LEGS]) {
        let mut trunk = false;
        let mut limb = [0u32; NUM_LEGS];
        let mut feet = [false; NUM_LEGS];
        let dt = self.world.integration_parameters.dt;
        for &(c, part) in &self.parts {
            let touching = self.world.narrow_phase.contact_pair(c, self.ground).is_some_and(|p| touches(p, dt));
            if !touching {
                continue;
            }
            match part {
                Part::Trunk => trunk = true,
                Part::Thigh(l) | Part::Calf(l) => limb[l] += 1,
                Part::Foot(l) => feet[l] = true,
                Part::Other => {}
            }
        }
        (trunk, limb, feet)
    }
}

/// Smallest normal contact force that counts as touching, N (legged_gym's 0.1 N).
pub const CONTACT_FORCE_THRESHOLD: f32 = 0.1;

/// Whether a contact pair is a real contact after a physics step of `dt`: the
/// solver pushed with more than [`CONTACT_FORCE_THRESHOLD`], or a contact point
/// penetrates (distance <= 0). rapier's `has_any_active_contact` is not this:
/// it is true for any solver contact, and solver contacts include speculative
/// ones up to the prediction distance away (a rear calf capsule's lower end
/// hovering ~2 cm above the ground, with zero impulse, counted as touching).
pub fn touches(pair: &ContactPair, dt: f32) -> bool {
    pair.total_impulse_magnitude() > CONTACT_FORCE_THRESHOLD * dt
        || pair.solver_manifolds().iter().any(|m| m.data.solver_contacts.iter().any(|s| s.dist <= 0.0))
}
