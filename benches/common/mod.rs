//! What the benches share.

use std::time::Duration;

use wgtrace::{Engine, FlatScene, Session, SessionOptions, StopRule};

/// Samples per second of `engine` on `scene` in a session: one warm-up pass, then passes
/// for `min_time`.
pub fn samples_per_second(engine: Engine, scene: &FlatScene, min_time: Duration) -> f64 {
    let opts = SessionOptions {
        passes: wgtrace::session::Passes::Uncapped,
        ..Default::default()
    };
    let mut session = Session::with_engine(scene.clone(), engine, opts).expect("session");
    let warm = StopRule {
        until: Some(1),
        ..Default::default()
    };
    session.run(&warm, |_| {}).expect("warm-up pass");
    let timed = StopRule {
        time_limit: Some(min_time),
        ..Default::default()
    };
    session
        .run(&timed, |_| {})
        .expect("passes")
        .progress
        .samples_per_second()
}
