//! bip-sched's tests in one binary: the analysis against a naive simulation of the
//! schedule, the priority rules, the checks, the picture.

mod analysis;
mod oracle;
mod svg;
