//! winit's input events made into the viewer's actions: drags of the pointer (orbit, or pan
//! with the middle or right button or Shift), the wheel, and the keys of `controls`. This
//! is the one place that reads winit's input; everything after it sees
//! `controls::Action` and `camera::Input`.

use winit::dpi::PhysicalPosition;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{Key as WinitKey, NamedKey};

use super::camera::{DragMode, Input};
use super::controls::{Action, key_action};

/// The pointer and the Shift key, for drags.
#[derive(Default)]
pub struct Pointer {
    at: Option<PhysicalPosition<f64>>,
    orbiting: bool,
    panning: bool,
    shift: bool,
}

impl Pointer {
    /// The action `event` asks for, if any; events that only move the pointer or change
    /// the buttons and modifiers held ask for none.
    pub fn action(&mut self, event: &WindowEvent) -> Option<Action> {
        match event {
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::MouseInput { state, button, .. } => {
                let down = *state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.orbiting = down,
                    MouseButton::Middle | MouseButton::Right => self.panning = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => return self.moved(*position),
            WindowEvent::CursorLeft { .. } => self.at = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    // Touchpads report pixels; about 40 make a notch.
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if notches != 0.0 {
                    return Some(Action::Camera(Input::Wheel(notches)));
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let name = match &event.logical_key {
                    WinitKey::Character(c) => Some(c.as_str()),
                    WinitKey::Named(NamedKey::Escape) => Some("escape"),
                    WinitKey::Named(NamedKey::Space) => Some("space"),
                    _ => None,
                };
                return name.and_then(key_action);
            }
            _ => {}
        }
        None
    }

    /// The drag a move of the pointer to `at` makes, if a button is held.
    fn moved(&mut self, at: PhysicalPosition<f64>) -> Option<Action> {
        let last = self.at.replace(at)?;
        let (dx, dy) = ((at.x - last.x) as f32, (at.y - last.y) as f32);
        let mode = if self.panning || (self.orbiting && self.shift) {
            DragMode::Pan
        } else if self.orbiting {
            DragMode::Orbit
        } else {
            return None;
        };
        (dx != 0.0 || dy != 0.0).then_some(Action::Camera(Input::Drag { mode, dx, dy }))
    }
}
