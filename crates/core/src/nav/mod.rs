//! The navigator and its time loop: the INS with its error-state filter
//! (`ins_filter`), one IMU step with its measurements (`navigator`, `timeline`), the
//! start (`start`) and the driver (`run`); the time-reversed driver of
//! post-processing (`backward`).

pub mod backward;
pub mod ins_filter;
pub mod navigator;
pub mod run;
pub(crate) mod start;
pub(crate) mod start_motion;
pub mod timeline;

#[cfg(test)]
mod backward_tests;
#[cfg(test)]
mod start_tests;
#[cfg(test)]
pub(crate) mod tests;
