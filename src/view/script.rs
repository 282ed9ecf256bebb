//! The viewer's input scripts (`gpurt view --script FILE`): one event per line, replayed
//! in order, so that a test or a demo drives the real window without a person.
//!
//! ```text
//! # orbit 90 pixels right and 20 up, dolly in two notches, print the camera
//! drag 90 -20
//! pan 10 0        # shift-drag: moves the focus
//! wheel 2
//! key c           # any key of `gpurt view --help`
//! wait 30         # let 30 frames be shown
//! ```

use std::path::Path;

use super::camera::{DragMode, Input};
use super::controls::{Action, key_action};
use crate::util::error::{Error, Result};

/// Largest script read: a script is typed by hand or written by a test.
const MAX_SCRIPT_BYTES: u64 = 1 << 20;

/// Most pixels one drag may move, and most notches one wheel event may turn.
const MAX_MOVE: f32 = 1e5;

/// Most frames one `wait` may wait.
const MAX_WAIT: u32 = 1_000_000;

/// One line of a script.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// What a mouse gesture or a key does.
    Action(Action),
    /// Show this many frames before the next event.
    Wait(u32),
}

/// Reads and parses a script file, read no further than `MAX_SCRIPT_BYTES` (a file's
/// length says nothing of a pipe or a device such as /dev/zero).
pub fn load(path: &Path) -> Result<Vec<Event>> {
    let text = crate::util::bounded::read(path, MAX_SCRIPT_BYTES)
        .map_err(|e| Error::io(path, e))?
        .ok_or_else(|| Error::Scene {
            file: path.display().to_string(),
            msg: format!("a script is at most {MAX_SCRIPT_BYTES} bytes; this one is longer"),
        })?;
    parse(&String::from_utf8_lossy(&text), &path.display().to_string())
}

/// Parses a script; errors name `file`, the line and the column.
pub fn parse(text: &str, file: &str) -> Result<Vec<Event>> {
    let mut events = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split('#').next().unwrap_or("");
        // Each word with the column (1-based) it starts at.
        let words: Vec<(usize, &str)> = code
            .split_whitespace()
            .map(|w| (w.as_ptr() as usize - line.as_ptr() as usize + 1, w))
            .collect();
        let Some(&(col, verb)) = words.first() else {
            continue;
        };
        let fail = |col: usize, msg: String| Error::Parse {
            file: file.to_owned(),
            line: i as u32 + 1,
            col: col as u32,
            msg,
            excerpt: Some(Box::new(crate::util::error::Excerpt::of_line(
                line.as_bytes(),
                col - 1,
                line[col - 1..]
                    .split_whitespace()
                    .next()
                    .map_or(0, str::len),
            ))),
        };
        let args = &words[1..];
        let arity = |n: usize| {
            if args.len() == n {
                Ok(())
            } else {
                let at = args.get(n).map_or(line.trim_end().len() + 1, |a| a.0);
                Err(fail(
                    at,
                    format!("'{verb}' takes {n} argument(s), got {}", args.len()),
                ))
            }
        };
        let number = |k: usize| -> Result<f32> {
            let (c, w) = args[k];
            match w.parse::<f32>() {
                Ok(v) if v.is_finite() && v.abs() <= MAX_MOVE => Ok(v),
                _ => Err(fail(
                    c,
                    format!("'{w}': expected a number of magnitude at most {MAX_MOVE}"),
                )),
            }
        };
        let event = match verb.to_lowercase().as_str() {
            "drag" | "pan" => {
                arity(2)?;
                let mode = if verb.eq_ignore_ascii_case("pan") {
                    DragMode::Pan
                } else {
                    DragMode::Orbit
                };
                Event::Action(Action::Camera(Input::Drag {
                    mode,
                    dx: number(0)?,
                    dy: number(1)?,
                }))
            }
            "wheel" => {
                arity(1)?;
                Event::Action(Action::Camera(Input::Wheel(number(0)?)))
            }
            "key" => {
                arity(1)?;
                let (c, name) = args[0];
                let action = key_action(name).ok_or_else(|| {
                    fail(
                        c,
                        format!("'{name}' is not a key of the viewer (see gpurt view --help)"),
                    )
                })?;
                Event::Action(action)
            }
            "wait" => {
                arity(1)?;
                let (c, w) = args[0];
                match w.parse::<u32>() {
                    Ok(n) if n <= MAX_WAIT => Event::Wait(n),
                    _ => {
                        return Err(fail(
                            c,
                            format!("'{w}': expected a frame count, 0 to {MAX_WAIT}"),
                        ));
                    }
                }
            }
            _ => {
                return Err(fail(
                    col,
                    format!("unknown event '{verb}' (expected drag, pan, wheel, key or wait)"),
                ));
            }
        };
        events.push(event);
    }
    Ok(events)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::camera::Key;

    #[test]
    fn every_event_parses() {
        let events = parse(
            "# a comment\n\ndrag 90 -20.5\npan 1 2 # trailing\nWHEEL -1\nkey W\nkey escape\nwait 3\n",
            "s",
        )
        .unwrap();
        assert_eq!(
            events,
            vec![
                Event::Action(Action::Camera(Input::Drag {
                    mode: DragMode::Orbit,
                    dx: 90.0,
                    dy: -20.5
                })),
                Event::Action(Action::Camera(Input::Drag {
                    mode: DragMode::Pan,
                    dx: 1.0,
                    dy: 2.0
                })),
                Event::Action(Action::Camera(Input::Wheel(-1.0))),
                Event::Action(Action::Camera(Input::Key(Key::Forward))),
                Event::Action(Action::Quit),
                Event::Wait(3),
            ]
        );
        assert_eq!(parse("", "s").unwrap(), vec![]);
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let cases = [
            ("drag 1\n", "s:1:7: 'drag' takes 2 argument(s), got 1"),
            ("wait 2\n  spin 3\n", "s:2:3: unknown event 'spin'"),
            ("key  z\n", "s:1:6: 'z' is not a key"),
            ("drag 1 nan\n", "s:1:8: 'nan': expected a number"),
            ("wheel 1e9\n", "s:1:7: '1e9': expected a number"),
            ("wait -1\n", "s:1:6: '-1': expected a frame count"),
            ("wheel 1 2\n", "s:1:9: 'wheel' takes 1 argument(s), got 2"),
        ];
        for (text, want) in cases {
            let e = parse(text, "s").unwrap_err().to_string();
            assert!(e.starts_with(want), "{text:?}: {e}");
        }
    }

    /// A script is read no further than its bound, whatever its length says: a device
    /// that never ends is refused, not read until memory runs out.
    #[test]
    fn an_endless_script_is_refused_at_its_bound() {
        let zero = Path::new("/dev/zero");
        if !zero.exists() {
            eprintln!("SKIPPED an_endless_script_is_refused_at_its_bound: no /dev/zero here");
            return;
        }
        let err = load(zero).unwrap_err().to_string();
        assert!(
            err.contains("/dev/zero") && err.contains("at most"),
            "{err}"
        );
    }
}
