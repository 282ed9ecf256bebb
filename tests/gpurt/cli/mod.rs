//! The `gpurt` command as a user runs it: exit codes, messages, files written or not.
//! `render` (single renders and what they write), `errors` (refusals, interrupts, GPU
//! faults), `tools` (`info`, `diff`), `farm` (batches, shards, `merge`).

mod errors;
mod farm;
mod render;
mod tools;
