//! What `quadcl` prints when run without a subcommand (`cargo run --release`)
//! and there is no terminal to open the workbench on: what there is to run,
//! with commands that work from the repository root.

/// Prints what there is to run.
pub fn run() {
    println!(
        "quadcl {}: continual reinforcement learning on a simulated quadruped.\n\n\
         The workbench needs a terminal (stdin and stdout are not one here). Things to run (cargo run --release -- ...):\n\
         \x20 tui [--run DIR] [--config FILE]                       the workbench, in a terminal (what `quadcl` alone opens)\n\
         \x20 run --config scenes/smoke.toml --out runs/smoke    a 3-task sequence in seconds: metrics.json, checkpoints\n\
         \x20 train --config scenes/train-base.toml --out runs/base [--resume]   the base walking policy (long)\n\
         \x20 eval --policy DIR --task none --episodes 32 --json     return, tracking errors, fall rate\n\
         \x20 eval --policy policies/base-a1-flat --task none         the shipped walking base policy\n\
         \x20 gait --policy policies/base-a1-flat --vx 0.5          its contact pattern (a trot)\n\
         \x20 masks --policy DIR [--json]                           which parameters each task claims\n\
         \x20 finetune --policy DIR --task TASK --shift FILE --out DIR   private-parameter fine-tuning\n\
         \x20 bench [--json]                                        simulator and network throughput\n\
         \x20 --help                                                every subcommand and option\n\n\
         Tasks are named like `none`, `crash:FL`, `invert:RR+noise:FR` (legs FL FR RL RR).",
        env!("CARGO_PKG_VERSION")
    );
}
