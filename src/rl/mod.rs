//! The learner: PPO with a privileged critic and a context estimator.
