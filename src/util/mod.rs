//! The small pieces every layer may use, which use no other layer: `error` (the one
//! error type), `atomic` (outputs written whole or not at all), `bounded` (small files
//! read no further than a bound), `console` (stdout that never panics), `fault` (faults
//! injected for the tests), `limits` (image, sample and reader limits and defaults).

pub mod atomic;
pub mod bounded;
pub mod console;
pub mod error;
pub mod fault;
pub mod limits;
