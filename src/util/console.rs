//! Standard output that never panics: `println!` panics when the reader has gone away
//! (`gpurt info scene.nff | head -1`, `... | true`); a command-line tool ends quietly
//! instead. What cannot be written is dropped, and the command finishes its work (a heat
//! map is still written) with its usual exit code.

use std::io::Write;

/// Writes to standard output, ignoring a closed or broken pipe.
pub fn out(args: std::fmt::Arguments) {
    let _ = std::io::stdout().lock().write_fmt(args);
}

/// `println!` that ignores a closed or broken standard output.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::util::console::out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` that ignores a closed or broken standard output.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::util::console::out(format_args!($($arg)*))
    };
}
