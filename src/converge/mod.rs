//! Convergence measurements: how error falls with samples and seconds, per sampler and
//! light-sampling strategy (and path length), against a reference image. `wgtrace
//! converge` drives [`run`]; the metrics and fits are plain functions the tests check on
//! synthetic data. One file per concern: the metrics, what a study is asked for, its
//! reference, what it measured, the study, the report and the plots.

pub mod config;
pub mod error;
pub mod metrics;
pub mod options;
pub mod plots;
pub mod reference;
pub mod report;
pub mod results;
pub mod study;

pub use config::Config;
pub use error::ConvergeError;
pub use metrics::{efficiency, first_crossing, fit_loglog, rel_mse, rmse};
pub use options::{ladder, Event, Options};
pub use reference::reference;
pub use report::write_report;
pub use results::{
    curve, to_reach, Measurement, Reach, ReferenceInfo, Study, MAX_EXTRAPOLATION, TARGETS,
};
pub use study::run;
