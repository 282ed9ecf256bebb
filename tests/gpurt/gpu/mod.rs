//! The GPU renderer against the CPU reference, and what it does when the device cannot or
//! will not: `agreement` (images pixel by pixel, and the comparer's self-test), `walks`
//! (every traversal, deep trees, texture layers), `counts` (rays and node fetches by kind,
//! against the CPU twin of each walk), `dispatch` (work cut into passes and
//! continued, the time budget), `wavefront` (the wavefront kernels against the one
//! kernel and the CPU), `faults` (limits, validation errors, lost devices). The
//! shared device and comparison live in `common::versus`.

mod agreement;
mod counts;
mod dispatch;
mod faults;
mod walks;
mod wavefront;
