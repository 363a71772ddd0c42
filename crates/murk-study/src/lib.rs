//! The study of Luesia et al. as a plan of independent render tasks, their reconstructions, metrics
//! against the renderer's ground truth, figures and an HTML report.

pub mod metrics;
