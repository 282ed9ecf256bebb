//! How an error reaches the terminal: `gpurt: ` and the error (which starts with what the
//! user gave: the file, with its line and column for a parse error), then, for a parse
//! error, the line it is in with a caret under the column, as rustc shows one.
//!
//! The excerpt is drawn by codespan-reporting, which naga already brings in for its own
//! WGSL errors (so it costs no new dependency), through its `Renderer`: the source line and
//! the caret alone, under our own first line, so that every message keeps the
//! `FILE:LINE:COL: message` form that editors jump to.

use codespan_reporting::diagnostic::{LabelStyle, Severity};
use codespan_reporting::term::termcolor::NoColor;
use codespan_reporting::term::{Chars, Config, Renderer};
use gpurt::Error;
use gpurt::util::error::Excerpt;

/// Prints `gpurt: {e}`, then the excerpt of a parse error; `suffix` ends the first line.
pub fn print_error(e: &Error, suffix: &str) {
    eprintln!("gpurt: {e}{suffix}");
    if let Error::Parse {
        line,
        excerpt: Some(x),
        ..
    } = e
    {
        eprint!("{}", excerpt(*line, x));
    }
}

/// The lines under an error at `line`:
///
/// ```text
///   |
/// 5 | angel 40
///   | ^^^^^
/// ```
pub fn excerpt(line: u32, x: &Excerpt) -> String {
    let config = Config {
        chars: Chars::ascii(),
        ..Config::default()
    };
    let mut out = NoColor::new(Vec::new());
    let padding = line.to_string().len();
    let label = [(LabelStyle::Primary, x.span.clone(), "")];
    let drawn = {
        let mut r = Renderer::new(&mut out, &config);
        r.render_snippet_empty(padding, Severity::Error, 0, &[])
            .and_then(|()| {
                r.render_snippet_source(
                    padding,
                    line as usize,
                    &x.text,
                    Severity::Error,
                    &label,
                    0,
                    &[],
                )
            })
    };
    match drawn {
        Ok(()) => String::from_utf8_lossy(&out.into_inner()).into_owned(),
        // Only a writer's failure can fail this, and a Vec does not fail.
        Err(_) => String::new(),
    }
}
