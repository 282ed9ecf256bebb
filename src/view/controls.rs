//! What the viewer's keys and script words do: one table for the window and for
//! `--script`, so that a scripted key does exactly what the same key does by hand.

use super::camera::{Input, Key};

/// What the window shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The progressive ray-traced image (the wireframe stands in until the first samples
    /// of a new view arrive).
    RayTraced,
    /// The wireframe alone; nothing is traced.
    Wireframe,
    /// The wireframe over the ray-traced image.
    Overlay,
}

impl Mode {
    /// The mode the mode key switches to.
    pub fn next(self) -> Mode {
        match self {
            Mode::RayTraced => Mode::Wireframe,
            Mode::Wireframe => Mode::Overlay,
            Mode::Overlay => Mode::RayTraced,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Mode::RayTraced => "ray traced",
            Mode::Wireframe => "wireframe",
            Mode::Overlay => "overlay",
        }
    }

    /// Whether this mode shows ray-traced samples (and so keeps the tracer busy).
    pub fn traces(self) -> bool {
        self != Mode::Wireframe
    }
}

/// What a key press does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Moves the camera.
    Camera(Input),
    /// Switches to the next display mode.
    NextMode,
    /// Prints the current camera as an NFF `v` block.
    PrintView,
    /// Writes the ray-traced image of the current view as a PNG.
    SavePng,
    /// Plays or pauses an animated scene.
    Play,
    /// Steps an animated scene by this many frames.
    Step(i8),
    Quit,
}

/// The keys, by the name a script uses (the character the key types, or `escape`), with
/// what they do; `gpurt view --help` prints this table.
pub const KEYS: [(&str, Action, &str); 18] = [
    ("w", Action::Camera(Input::Key(Key::Forward)), "fly forward"),
    ("s", Action::Camera(Input::Key(Key::Back)), "fly back"),
    ("a", Action::Camera(Input::Key(Key::Left)), "fly left"),
    ("d", Action::Camera(Input::Key(Key::Right)), "fly right"),
    ("q", Action::Camera(Input::Key(Key::Down)), "fly down"),
    ("e", Action::Camera(Input::Key(Key::Up)), "fly up"),
    (
        "+",
        Action::Camera(Input::Key(Key::ZoomIn)),
        "narrow the field of view",
    ),
    (
        "=",
        Action::Camera(Input::Key(Key::ZoomIn)),
        "narrow the field of view",
    ),
    (
        "-",
        Action::Camera(Input::Key(Key::ZoomOut)),
        "widen the field of view",
    ),
    (
        "r",
        Action::Camera(Input::Key(Key::Reset)),
        "back to the scene's camera",
    ),
    ("m", Action::NextMode, "ray traced / wireframe / overlay"),
    ("c", Action::PrintView, "print the camera as an NFF v block"),
    ("p", Action::SavePng, "write the ray-traced view as a PNG"),
    ("space", Action::Play, "play or pause an animated scene"),
    (".", Action::Step(1), "an animated scene's next frame"),
    (",", Action::Step(-1), "an animated scene's previous frame"),
    ("escape", Action::Quit, "quit"),
    ("x", Action::Quit, "quit"),
];

/// What the key named `name` does (case-insensitive), if anything.
pub fn key_action(name: &str) -> Option<Action> {
    let name = name.to_lowercase();
    KEYS.iter().find(|(k, ..)| *k == name).map(|(_, a, _)| *a)
}

/// The key table as help text, one key per line.
pub fn key_help() -> String {
    let mut s = String::from(
        "Mouse: drag to orbit the focus, shift-drag or middle-drag to pan, wheel to dolly.\nKeys:\n",
    );
    for (key, _, what) in KEYS {
        s.push_str(&format!("  {key:<7} {what}\n"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_listed_once_and_found_in_either_case() {
        for (i, (k, a, _)) in KEYS.iter().enumerate() {
            assert!(KEYS[..i].iter().all(|(other, ..)| other != k), "{k} twice");
            assert_eq!(key_action(k), Some(*a));
            assert_eq!(key_action(&k.to_uppercase()), Some(*a));
        }
        assert_eq!(key_action("z"), None);
    }

    #[test]
    fn the_mode_key_cycles_through_all_three_modes() {
        let mut m = Mode::RayTraced;
        let mut seen = vec![m];
        for _ in 0..3 {
            m = m.next();
            seen.push(m);
        }
        assert_eq!(seen[3], Mode::RayTraced);
        assert!(seen.contains(&Mode::Wireframe) && seen.contains(&Mode::Overlay));
    }
}
