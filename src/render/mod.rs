//! Pictures of the simulated world without a GPU: a ray-cast frame of a `LocomotionEnv`
//! ([`render`]) from a tracking [`Camera`], text on frames, PNG files, and MP4 videos through an
//! `ffmpeg` found on PATH ([`VideoWriter`]). Used by `quadcl record --format mp4`, `quadcl eval
//! --video`, the Python package's `render_mode="rgb_array"` and `quadcl bench --only render`.

pub mod camera;
pub mod font;
pub mod frame;
pub mod raycast;
pub mod scene;
pub mod video;

pub use camera::Camera;
pub use frame::{encode_png, Frame};
pub use raycast::render;
pub use scene::Scene;
pub use video::VideoWriter;

/// A frame of `env` as its last step left it, seen by `camera` (the scene, then [`render`]).
pub fn frame_of(
    env: &crate::sim::LocomotionEnv,
    camera: &Camera,
    width: usize,
    height: usize,
) -> anyhow::Result<Frame> {
    render(&Scene::of_env(env), camera, width, height)
}
