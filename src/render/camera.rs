//! The tracking camera: it follows the trunk across the ground (not up and down, so the gait's
//! bounce shows) from a fixed distance, elevation and azimuth in the world, with a pinhole lens.

use rapier3d::math::Vector;

/// Where the camera looks from, relative to the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// From the point it tracks, metres.
    pub distance: f32,
    /// Above the horizontal, degrees.
    pub elevation_deg: f32,
    /// Around the vertical from the world's +x (the robot's walking direction at the start),
    /// degrees: -90 looks at the robot's right side.
    pub azimuth_deg: f32,
    /// The vertical field of view, degrees.
    pub fov_deg: f32,
    /// The height the camera aims at, metres (about the trunk's when it stands).
    pub aim_height: f32,
}

impl Default for Camera {
    /// Front right of the robot, a little above it: all four legs and the trunk in view.
    fn default() -> Self {
        Self { distance: 1.5, elevation_deg: 18.0, azimuth_deg: -60.0, fov_deg: 45.0, aim_height: 0.25 }
    }
}

/// One frame's rays: the eye and the direction through each pixel's centre.
#[derive(Debug, Clone, Copy)]
pub struct Rays {
    pub eye: Vector,
    forward: Vector,
    right: Vector,
    up: Vector,
    /// tan(fov / 2): the half height of the image plane at distance 1.
    half_height: f32,
    width: usize,
    height: usize,
}

impl Camera {
    /// The rays of a `width` x `height` frame looking at the trunk's ground position `trunk`.
    pub fn rays(&self, trunk: Vector, width: usize, height: usize) -> Rays {
        let target = Vector::new(trunk.x, trunk.y, self.aim_height);
        let (el, az) = (self.elevation_deg.to_radians(), self.azimuth_deg.to_radians());
        let back = Vector::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        let eye = target + back * self.distance;
        let forward = -back;
        let right = forward.cross(Vector::Z).normalize();
        let up = right.cross(forward);
        Rays { eye, forward, right, up, half_height: (self.fov_deg.to_radians() / 2.0).tan(), width, height }
    }
}

impl Rays {
    /// The unit direction through the centre of pixel (x, y), y from the top.
    pub fn direction(&self, x: usize, y: usize) -> Vector {
        let aspect = self.width as f32 / self.height as f32;
        let u = ((x as f32 + 0.5) / self.width as f32 * 2.0 - 1.0) * self.half_height * aspect;
        let v = (1.0 - (y as f32 + 0.5) / self.height as f32 * 2.0) * self.half_height;
        (self.forward + self.right * u + self.up * v).normalize()
    }
}
