//! Continual learning around the learner: task sequences, the continual
//! measures (Continual World conventions, METHOD.md section 4).

pub mod metrics;
