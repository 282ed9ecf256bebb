//! How the readers read (`ReadOptions`): what a caller (the command line, a binding over
//! the library) chooses about input they would otherwise refuse. A leaf of its own, so that
//! the readers and `scene::load*` share it without importing each other.

/// How the readers read: what a caller (the command line, a binding over the library)
/// chooses about input they would otherwise refuse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// An NFF keyword gpurt does not know (`Q`, `fp`, `obj`, from other tracers' dialects)
    /// is skipped, with what follows it up to the next keyword gpurt knows, and one
    /// warning each, instead of ending the read with an error.
    pub lenient: bool,
    /// Bytes of the window every reader reads its file through (`None`: the usual 256
    /// KiB). The tests read through tiny ones, so that the window's ends cut tokens,
    /// lines and binary records everywhere.
    pub window: Option<usize>,
}
