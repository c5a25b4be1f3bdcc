//! What `quadcl` prints when run without a subcommand.

/// Prints what there is to run. (The TUI will open here once it exists.)
pub fn run() {
    println!(
        "quadcl {}: continual reinforcement learning on a simulated quadruped.\n\n\
         There is no terminal workbench (TUI) yet. Things to run now:\n\
         \x20 quadcl bench            throughput of the simulator and of the masked networks\n\
         \x20 quadcl masks --policy DIR   which parameters each task of a policy claims\n\
         \x20 quadcl --help           every subcommand\n",
        env!("CARGO_PKG_VERSION")
    );
}
