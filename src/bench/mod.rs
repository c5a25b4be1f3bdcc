//! The figures printed by `quadcl bench`: each section adds its keys to one
//! JSON object, so scripts can read them by name.

pub mod accuracy;
pub mod env;
pub mod gemm;
pub mod nn;
pub mod ppo;
pub mod record;
pub mod render;
pub mod tui;

/// CPU seconds (user + system) from a Linux `/proc/.../stat` file: `/proc/self/stat` for the
/// whole process, `/proc/thread-self/stat` for the calling thread. Fields 14 and 15 in clock
/// ticks (100 a second on Linux); None where the file is missing or malformed.
pub(crate) fn cpu_seconds(stat_file: &str) -> Option<f64> {
    let stat = std::fs::read_to_string(stat_file).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count after it.
    let fields: Vec<&str> = stat[stat.rfind(')')? + 1..].split_whitespace().collect();
    // fields[0] is field 3 (the state), so fields 14 and 15 are at 11 and 12.
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
