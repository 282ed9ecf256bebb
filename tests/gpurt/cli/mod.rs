//! The `gpurt` command as a user runs it: exit codes, messages, files written or not.
//! `render` (single renders and what they write), `errors` (refusals, interrupts, GPU
//! faults), `tools` (`info`, `diff`, `bench`, `tune`), `farm` (batches, shards, `merge`),
//! `sequence` (an animated scene's frames), `shell`
//! (completions, the manual page, suggestions, threads).

mod errors;
mod farm;
mod render;
mod sequence;
mod shell;
mod tools;
