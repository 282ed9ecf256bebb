//! Scene input: the NFF reader (with the P3D dialect and our extensions), STL, OBJ, PLY,
//! gzip and bare meshes, checked against the shared SPD/P3D scenes, hand-written inputs for
//! every error class, and random mutations that must never make a reader panic. One file a
//! subject: `shared` (the SPD and P3D files), `statements` and `view` (NFF as it is read),
//! `errors` (positions, limits, mutations), `mesh` (STL, OBJ, `mesh`, bare meshes), `ply`, `gltf`,
//! `sniff` (formats told by their first bytes), `gzip`, `stream` (reading through a buffer
//! of fixed size), `materials` (OBJ `.mtl`, `--lenient`), `aff` (BART's animated NFF).

mod aff;
mod errors;
mod gltf;
mod gzip;
pub mod materials;
mod mesh;
mod ply;
mod shared;
mod sniff;
mod statements;
mod stream;
mod view;
