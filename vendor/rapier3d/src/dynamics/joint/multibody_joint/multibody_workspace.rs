use crate::alloc_prelude::*;
use crate::dynamics::RigidBodyVelocity;
use crate::math::{DVector, Real};

/// A temporary workspace for various updates of the multibody.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug)]
pub(crate) struct MultibodyWorkspace {
    pub accs: Vec<RigidBodyVelocity<Real>>,
    pub ndofs_vec: DVector,
    /// Generalized forces from positions and external inputs (`update_acceleration`).
    pub pos_forces: DVector,
    /// The full generalized forces before the solve (`update_acceleration`).
    pub gen_forces: DVector,
    /// The energy guard's velocities, forces, accelerations and products, reordered.
    pub guard_v: DVector,
    pub guard_f: DVector,
    pub guard_f_pos: DVector,
    pub guard_a: DVector,
    pub guard_m_a: DVector,
    pub guard_m_v: DVector,
}

impl MultibodyWorkspace {
    /// Create an empty workspace.
    pub fn new() -> Self {
        MultibodyWorkspace {
            accs: Vec::new(),
            ndofs_vec: DVector::zeros(0),
            pos_forces: DVector::zeros(0),
            gen_forces: DVector::zeros(0),
            guard_v: DVector::zeros(0),
            guard_f: DVector::zeros(0),
            guard_f_pos: DVector::zeros(0),
            guard_a: DVector::zeros(0),
            guard_m_a: DVector::zeros(0),
            guard_m_v: DVector::zeros(0),
        }
    }

    /// Resize the workspace so it is enough for `nlinks` links.
    pub fn resize(&mut self, nlinks: usize, ndofs: usize) {
        self.accs.resize(nlinks, RigidBodyVelocity::zero());
        self.ndofs_vec = DVector::zeros(ndofs)
    }
}
