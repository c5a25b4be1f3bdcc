//! What a Rerun recording logs once, as static data, before the first step:
//!
//! | entity | archetype | content |
//! | --- | --- | --- |
//! | `/` | `ViewCoordinates` | right-handed, z up (the simulator's world) |
//! | `robot/NAME/...` | the URDF importer's | the robot's links (visual and collision shapes, meshes), each in its link's frame |
//! | `tf_static` | `Transform3D` rows | the URDF's joint origins (the importer's), overridden per step on `transforms` |
//! | `world/ground` | `LineStrips3D` | a 0.25 m grid, 3 m across, around the start |
//! | `task` | `TextDocument` | the task, its perturbation, the policy |
//! | `masks` | `AnnotationContext` | the element views' labels and colours (the workbench's) |
//! | `masks/LAYER` | `SegmentationImage` | the task's view of every element of a layer, (out, in) |
//!
//! The default layout ([`blueprint`]): the 3D view large on the left with the
//! task below it; the reward terms, tracking errors, joints and masks in tabs
//! on the right.
//!
//! The robot goes through Rerun's own URDF importer ([`UrdfTree::emit`], the code
//! `RecordingStream::log_file_from_path` runs), called in this thread so that a
//! file it cannot read is an error here rather than a warning in the viewer.

use crate::nn::{ElementView, LayerView};
use crate::sim::{PerturbationKind, RobotModel};
use ::rerun::external::re_importer::UrdfTree;
use ::rerun::external::urdf_rs;
use ::rerun::{EntityPath, RecordingStream, TimePoint};
use anyhow::Context;

/// The entity every link's shapes sit under.
pub const ROBOT_ENTITY: &str = "robot";

/// What a recording shows besides the robot's motion.
#[derive(Debug, Clone)]
pub struct RerunScene {
    /// The task's name (`crash:FR`, ...).
    pub task: String,
    /// Where the policy came from (for the task text).
    pub policy: String,
    /// The policy's masks as the task sees them (empty for a dense network).
    pub masks: Vec<LayerView>,
}

/// The robot as Rerun's URDF importer sees it, and the 12 leg joints in leg-joint order.
pub(crate) struct RerunRobot {
    pub tree: UrdfTree,
    pub leg_joints: Vec<urdf_rs::Joint>,
    /// The root link's frame (the floating base moves it in the world).
    pub root_frame: String,
}

impl RerunRobot {
    /// The importer's tree of `robot`'s file; a file the importer's strict reader refuses (our
    /// reader tolerates more) falls back to the simulator's own reading of it (collision shapes,
    /// primitives for meshes).
    pub fn of(robot: &RobotModel) -> anyhow::Result<Self> {
        let prefix = Some(EntityPath::from(ROBOT_ENTITY));
        let tree = match UrdfTree::from_file_path(&robot.path, prefix.clone()) {
            Ok(tree) => tree,
            Err(_) => UrdfTree::new(robot.urdf.clone(), robot.path.parent().map(|p| p.to_path_buf()), prefix)
                .with_context(|| format!("{}: Rerun's URDF importer cannot read it", robot.path.display()))?,
        };
        let leg_joints = robot
            .joints
            .iter()
            .map(|j| {
                tree.get_joint_by_name(&j.name).cloned().with_context(|| {
                    format!("{}: Rerun's URDF importer has no joint {:?}", robot.path.display(), j.name)
                })
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        let trunk = &robot.urdf.links[robot.trunk_link].name;
        let root_frame = tree.root().name.clone();
        anyhow::ensure!(
            *trunk == root_frame,
            "{}: the simulator's trunk {trunk:?} is not the URDF's root link {root_frame:?}",
            robot.path.display()
        );
        Ok(Self { tree, leg_joints, root_frame })
    }
}

/// Logs the static scene: coordinates, robot, ground, task text and masks.
pub(crate) fn log_scene(rec: &RecordingStream, robot: &RerunRobot, scene: &RerunScene) -> anyhow::Result<()> {
    rec.log_static("/", &::rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
    let mut chunks = Vec::new();
    robot.tree.emit(&mut |chunk| chunks.push(chunk), &TimePoint::default(), true)?;
    rec.send_chunks(chunks);
    rec.log_static("world/ground", &ground_grid(1.5, 0.25))?;
    rec.log_static(
        "task",
        &::rerun::TextDocument::new(task_text(scene)).with_media_type(::rerun::MediaType::markdown()),
    )?;
    if !scene.masks.is_empty() {
        let classes = ElementView::ALL.map(|v| {
            let (r, g, b) = v.rgb();
            (v as u16, v.label(), ::rerun::Rgba32::from_rgb(r, g, b))
        });
        rec.log_static("masks", &::rerun::AnnotationContext::new(classes))?;
        for layer in &scene.masks {
            let [out, inp] = layer.shape;
            let format = ::rerun::datatypes::ImageFormat::segmentation(
                [inp as u32, out as u32],
                ::rerun::datatypes::ChannelDatatype::U8,
            );
            let image = ::rerun::SegmentationImage::new(layer.codes.clone(), format);
            rec.log_static(format!("masks/{}", layer.layer.replace('.', "_")), &image)?;
        }
    }
    Ok(())
}

/// The default layout of the viewer for `scene`.
pub(crate) fn blueprint(scene: &RerunScene) -> ::rerun::blueprint::Blueprint {
    use ::rerun::blueprint::{Blueprint, ContainerLike, Horizontal, Spatial2DView, Spatial3DView, Tabs};
    use ::rerun::blueprint::{TextDocumentView, TimeSeriesView, Vertical};
    let series = |name: &str, origin: &str| -> ContainerLike { TimeSeriesView::new(name).with_origin(origin).into() };
    let robot = Spatial3DView::new("robot")
        .with_contents(["/robot/**", "/world/**", "/transforms", "/tf_static"].map(String::from));
    let left = Vertical::new([robot.into(), TextDocumentView::new("task").with_origin("/task").into()])
        .with_row_shares([4.0, 1.0]);
    let mut right: Vec<ContainerLike> = vec![
        Tabs::new([series("reward terms", "/reward/terms"), series("reward", "/reward/total")]).into(),
        Tabs::new([
            series("tracking", "/tracking"),
            series("command", "/command"),
            series("velocity", "/base_velocity"),
        ])
        .into(),
        Tabs::new([series("torques", "/joints/torque"), series("joint angles", "/joints/position")]).into(),
    ];
    if !scene.masks.is_empty() {
        let views = scene.masks.iter().map(|l| {
            let name = l.layer.replace('.', "_");
            Spatial2DView::new(format!("masks {}", l.layer)).with_origin(format!("/masks/{name}")).into()
        });
        right.push(Tabs::new(views).into());
    }
    Blueprint::new(Horizontal::new([left.into(), Vertical::new(right).into()]).with_column_shares([3.0, 2.0]))
}

/// Grid lines every `step` metres over [-half, half] in x and y, at z = 0.
fn ground_grid(half: f32, step: f32) -> ::rerun::LineStrips3D {
    let n = (half / step).round() as i32;
    let lines = (-n..=n).flat_map(|i| {
        let c = i as f32 * step;
        [[[c, -half, 0.0], [c, half, 0.0]], [[-half, c, 0.0], [half, c, 0.0]]]
    });
    ::rerun::LineStrips3D::new(lines.collect::<Vec<_>>())
        .with_colors([::rerun::Color::from_rgb(90, 90, 90)])
        .with_radii([0.004])
}

/// The task text: name, what each perturbed leg suffers, the policy.
fn task_text(scene: &RerunScene) -> String {
    let what = match scene.task.parse::<crate::sim::Perturbation>() {
        Ok(p) if p.is_none() => "no leg perturbed".to_string(),
        Ok(p) => p
            .items()
            .iter()
            .map(|(kind, leg)| {
                let effect = match kind {
                    PerturbationKind::Crash => "action held at zero (a broken leg)",
                    PerturbationKind::Invert => "action negated (an inverted leg)",
                    PerturbationKind::Noise => "Gaussian noise added to its action",
                };
                format!("- {}: {effect}", leg.name())
            })
            .collect::<Vec<_>>()
            .join("\n"),
        Err(_) => String::new(),
    };
    let masks = if scene.masks.is_empty() {
        "a dense network: no masks".to_string()
    } else {
        let legend: Vec<String> = ElementView::ALL.iter().map(|v| v.label().to_string()).collect();
        format!("masks per layer under `masks/` (rows: outputs, columns: inputs): {}", legend.join(", "))
    };
    format!("# Task {}\n\n{what}\n\nPolicy: `{}`\n\n{masks}\n", scene.task, scene.policy)
}
