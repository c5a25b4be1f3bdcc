//! The binary's log output: the library's WARN and ERROR `tracing` events
//! (for example a URDF mesh that was skipped) printed to stderr as
//! "warning: ..." / "error: ...". A minimal subscriber, so that no extra
//! dependency is needed; spans are ignored, lower levels are dropped.

use std::fmt::Write as _;
use std::io::Write;
use std::sync::Mutex;
use tracing::field::{Field, Visit};
use tracing::{span, Event, Level, Metadata, Subscriber};

/// Writes WARN and ERROR events, one line each, to `out`.
pub struct StderrLog<W: Write + Send + 'static> {
    out: Mutex<W>,
}

impl<W: Write + Send + 'static> StderrLog<W> {
    pub fn new(out: W) -> Self {
        Self { out: Mutex::new(out) }
    }
}

/// The event's message, then its other fields as ` name=value`.
#[derive(Default)]
struct Line(String);

impl Visit for Line {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            let _ = write!(self.0, "{value:?}");
        } else {
            let _ = write!(self.0, " {}={value:?}", field.name());
        }
    }
}

impl<W: Write + Send + 'static> Subscriber for StderrLog<W> {
    fn enabled(&self, metadata: &Metadata<'_>) -> bool {
        // tracing orders levels by verbosity: WARN and ERROR are the least verbose.
        *metadata.level() <= Level::WARN
    }

    fn new_span(&self, _: &span::Attributes<'_>) -> span::Id {
        span::Id::from_u64(1)
    }

    fn record(&self, _: &span::Id, _: &span::Record<'_>) {}

    fn record_follows_from(&self, _: &span::Id, _: &span::Id) {}

    fn event(&self, event: &Event<'_>) {
        let mut line = Line::default();
        event.record(&mut line);
        let kind = if *event.metadata().level() == Level::ERROR { "error" } else { "warning" };
        if let Ok(mut out) = self.out.lock() {
            let _ = writeln!(out, "{kind}: {}", line.0);
        }
    }

    fn enter(&self, _: &span::Id) {}

    fn exit(&self, _: &span::Id) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[derive(Clone, Default)]
    struct Shared(Arc<Mutex<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().write(buf)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_skipped_urdf_mesh_is_a_visible_warning() {
        let a1 = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/a1.urdf")).unwrap();
        let text = a1.replacen(
            "</collision>",
            "</collision>\n    <collision><geometry><mesh filename=\"meshes/missing.dae\"/></geometry></collision>",
            1,
        );
        let buf = Shared::default();
        tracing::subscriber::with_default(StderrLog::new(buf.clone()), || {
            tracing::info!("not shown");
            quadcl::sim::RobotModel::from_urdf_str(&text, std::path::Path::new("robot.urdf")).unwrap();
        });
        let printed = String::from_utf8(buf.0.lock().unwrap().clone()).unwrap();
        assert!(
            printed.starts_with("warning: robot.urdf: link 'trunk'") && printed.contains("missing.dae"),
            "{printed}"
        );
        assert!(!printed.contains("not shown"), "{printed}");
    }
}
