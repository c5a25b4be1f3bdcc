//! The simulated quadruped, in rapier3d only: knows nothing of networks or UI.
