//! The library's commands over a `Renderer` or a scene's buffers, each what one command
//! line subcommand does, never taking clap's types: `run` (one scene: read, pack, one
//! frame timed), `batch` and `shard` (many scenes, a farm's share of them), `sequence` (an animated
//! scene's frames), `bench` (the
//! passes of a scene timed by kind of ray), `tune` (the GPU strategies timed, the fastest
//! kept) and `info` (what a scene holds).

#[cfg(feature = "native")]
pub mod batch;
#[cfg(feature = "native")]
pub mod bench;
pub mod info;
#[cfg(feature = "native")]
pub mod run;
#[cfg(feature = "native")]
pub mod sequence;
#[cfg(feature = "native")]
pub mod shard;
#[cfg(feature = "native")]
pub mod tune;
