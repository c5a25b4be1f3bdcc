//! Every random stream of quadcl, derived from one master seed in one place.
//!
//! A stream's seed depends only on (seed it derives from, [`Stream`]), never on
//! a stream carried over, so a run interrupted at a boundary and resumed draws
//! exactly what it would have drawn. Each arm keeps the formula the shipped
//! policies and runs were made with, so their figures reproduce.

/// A random stream, named by what it drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Member `index` of a batch of environments (`sim::VecEnv`): its resets,
    /// commands and randomisation. Derived from the batch's seed.
    Env(usize),
    /// `quadcl train`'s learner stream (minibatches, action noise, mask draws)
    /// of a run that starts at `iteration` (0: a fresh run). A run resumed at
    /// `iteration > 0` from a checkpoint without a training state (written before
    /// resumes were exact) also seeds its environments with it; an exact resume
    /// restores the interrupted run's streams instead. Derived from the master seed.
    Trainer(usize),
    /// Every stream of training step `step` of a sequence (learner, optimiser,
    /// mask draws). Derived from the master seed.
    SequenceStep(usize),
    /// The fixed evaluation of distinct task `task` of a sequence: the same
    /// after every step, so recall can be compared bit for bit. Derived from the master seed.
    SequenceEval(usize),
    /// The environment batch of one training step. Derived from the step's seed.
    StepEnvs,
    /// The draw of `init = "random"` related tasks. Derived from the step's seed.
    RandomRelated,
    /// Sim-to-real fine-tuning's training step. Derived from its `--seed`.
    Sim2RealTrain,
    /// Sim-to-real fine-tuning's evaluation of task `task`, before and after. Derived from its `--seed`.
    Sim2RealEval(usize),
    /// The resampling of seeds behind a sweep's bootstrap intervals (`quadcl sweep collect`).
    /// Derived from a fixed seed, so a collected table is the same every time.
    Bootstrap,
    /// The redraw of a base policy's vacant weights (`[run] base_vacant = "redrawn"`). Derived
    /// from the master seed.
    BaseVacant,
}

/// The seed of `stream`, derived from `seed` (the master seed or the seed the
/// stream's doc names).
pub fn derive_seed(seed: u64, stream: Stream) -> u64 {
    match stream {
        Stream::Env(index) => {
            splitmix64(seed ^ (index as u64).wrapping_mul(GOLDEN).wrapping_add(0x6a09_e667_f3bc_c909))
        }
        Stream::Trainer(iteration) => seed ^ 0x5eed_1ea7_0000_0001 ^ (iteration as u64).wrapping_mul(GOLDEN),
        Stream::SequenceStep(step) => mix(seed, 1, step as u64),
        Stream::SequenceEval(task) => mix(seed, 2, task as u64),
        Stream::RandomRelated => mix(seed, 3, 0),
        Stream::StepEnvs => mix(seed, 10, 0),
        Stream::Sim2RealTrain => mix(seed, 20, 0),
        Stream::Sim2RealEval(task) => mix(seed, 21, task as u64),
        Stream::Bootstrap => mix(seed, 30, 0),
        Stream::BaseVacant => mix(seed, 40, 0),
    }
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A 64-bit mix of a seed, a purpose and an index.
fn mix(seed: u64, purpose: u64, index: u64) -> u64 {
    splitmix64(seed ^ purpose.wrapping_mul(GOLDEN) ^ index.wrapping_mul(0xbf58_476d_1ce4_e5b9))
}

/// The splitmix64 finaliser.
fn splitmix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_of_one_seed_differ_and_repeat() {
        let streams = [
            Stream::Env(0),
            Stream::Env(1),
            Stream::Trainer(0),
            Stream::Trainer(25),
            Stream::SequenceStep(0),
            Stream::SequenceEval(0),
            Stream::StepEnvs,
            Stream::RandomRelated,
            Stream::Sim2RealTrain,
            Stream::Sim2RealEval(0),
            Stream::Bootstrap,
            Stream::BaseVacant,
        ];
        let seeds: Vec<u64> = streams.iter().map(|&s| derive_seed(7, s)).collect();
        for (i, a) in seeds.iter().enumerate() {
            assert!(seeds[i + 1..].iter().all(|b| b != a), "stream {:?} repeats another", streams[i]);
        }
        assert_eq!(seeds, streams.iter().map(|&s| derive_seed(7, s)).collect::<Vec<_>>());
        assert_ne!(derive_seed(7, Stream::Env(0)), derive_seed(8, Stream::Env(0)));
    }
}
