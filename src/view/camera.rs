//! The viewer's camera controller: an orbit camera around a focus point, driven by plain
//! input events (no windowing types), so that it can be tested without a window.
//!
//! It moves an NFF `Camera` (`from`, `at`, `up`, `angle`): `at` is the focus, `up` the
//! scene's world up, which never changes. Orbiting yaws about the world up axis and
//! pitches about the camera's own right axis, stopping short of the poles so that the
//! view never flips; the ray tracer and the wireframe both read the resulting `Camera`.

use glam::{Quat, Vec3};

use crate::frame;
use crate::scene::Camera;

/// How close (in degrees) the view direction may come to the world up axis or its
/// opposite: at the pole itself the camera's right axis is undefined.
const POLE_MARGIN_DEG: f32 = 1.0;

/// Degrees the camera orbits per pixel dragged, per image height.
const ORBIT_DEG_PER_HEIGHT: f32 = 180.0;

/// One wheel notch moves the eye this fraction of its distance to the focus.
const DOLLY_PER_NOTCH: f32 = 0.1;

/// One fly key press moves eye and focus this fraction of their distance.
const FLY_STEP: f32 = 0.05;

/// One field-of-view key press changes the angle by this many degrees.
const FOV_STEP_DEG: f32 = 5.0;

/// A key the controller understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// Fly forward, left, back, right, down, up (W A S D Q E).
    Forward,
    Left,
    Back,
    Right,
    Down,
    Up,
    /// Narrow or widen the field of view.
    ZoomIn,
    ZoomOut,
    /// Back to the scene's camera.
    Reset,
}

/// What a drag does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DragMode {
    Orbit,
    Pan,
}

/// A plain input event, in pixels of the image the camera renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    Drag {
        mode: DragMode,
        dx: f32,
        dy: f32,
    },
    /// Wheel notches; positive moves towards the focus.
    Wheel(f32),
    Key(Key),
}

/// The orbit camera: the current view and the scene's, to reset to.
#[derive(Clone, Debug, PartialEq)]
pub struct OrbitCamera {
    pub camera: Camera,
    home: Camera,
}

impl OrbitCamera {
    /// Takes `camera` (an animated scene's at a new frame) as the scene's camera, and
    /// moves the view there too unless it had been moved away from the old one. The view
    /// keeps its size.
    pub fn follow(&mut self, camera: Camera) {
        let sized = |c: &Camera| Camera {
            width: 0,
            height: 0,
            ..c.clone()
        };
        let at_home = sized(&self.camera) == sized(&self.home);
        let (w, h) = (self.camera.width, self.camera.height);
        self.home = camera.clone();
        if at_home {
            self.camera = Camera {
                width: w,
                height: h,
                ..camera
            };
        }
    }

    /// Starts at the scene's camera, orbiting its `at`. An `up` not perpendicular to the
    /// view is kept as the world up axis, as NFF intends.
    pub fn new(camera: Camera) -> Self {
        OrbitCamera {
            home: camera.clone(),
            camera,
        }
    }

    /// Applies one event. Returns whether the view changed (accumulation restarts).
    pub fn apply(&mut self, input: Input) -> bool {
        let before = self.camera.clone();
        let height = self.camera.height.max(1) as f32;
        match input {
            Input::Drag {
                mode: DragMode::Orbit,
                dx,
                dy,
            } => {
                let per_px = ORBIT_DEG_PER_HEIGHT / height;
                self.orbit(-dx * per_px, -dy * per_px);
            }
            Input::Drag {
                mode: DragMode::Pan,
                dx,
                dy,
            } => {
                // One pixel at the focus distance, so the focus follows the pointer.
                let px =
                    self.distance() * frame::pixel_pitch(self.camera.angle, self.camera.height);
                let (_, right, up) = self.basis();
                self.translate(-dx * px * right + dy * px * up);
            }
            Input::Wheel(notches) => {
                let d = self.distance() * (1.0 - DOLLY_PER_NOTCH).powf(notches);
                self.camera.from = self.camera.at - self.forward() * d.max(1e-6);
            }
            Input::Key(key) => {
                let step = self.distance() * FLY_STEP;
                let (forward, right, up) = self.basis();
                match key {
                    Key::Forward => self.translate(forward * step),
                    Key::Back => self.translate(-forward * step),
                    Key::Right => self.translate(right * step),
                    Key::Left => self.translate(-right * step),
                    Key::Up => self.translate(up * step),
                    Key::Down => self.translate(-up * step),
                    Key::ZoomIn => self.set_angle(self.camera.angle - FOV_STEP_DEG),
                    Key::ZoomOut => self.set_angle(self.camera.angle + FOV_STEP_DEG),
                    Key::Reset => self.camera = self.home.clone(),
                }
            }
        }
        self.camera != before
    }

    /// Turns the eye about the focus: `yaw_deg` about the world up axis, `pitch_deg` about
    /// the camera's right axis, stopping `POLE_MARGIN_DEG` short of either pole.
    pub fn orbit(&mut self, yaw_deg: f32, pitch_deg: f32) {
        let world_up = self.world_up();
        let offset = self.camera.from - self.camera.at;
        let offset = Quat::from_axis_angle(world_up, yaw_deg.to_radians()) * offset;
        // The angle between the offset and the world up axis, kept inside the margin.
        let polar = offset.angle_between(world_up).to_degrees();
        let lo = POLE_MARGIN_DEG;
        let hi = 180.0 - POLE_MARGIN_DEG;
        let target = (polar - pitch_deg).clamp(lo.min(polar), hi.max(polar));
        let right = (-offset).cross(world_up).normalize_or_zero();
        let offset = if right == Vec3::ZERO {
            offset
        } else {
            Quat::from_axis_angle(right, (polar - target).to_radians()) * offset
        };
        self.camera.from = self.camera.at + offset;
    }

    /// The NFF `v` block of the current view, ready to paste into a scene.
    pub fn nff_view(&self) -> String {
        let c = &self.camera;
        let v = |p: Vec3| format!("{} {} {}", p.x, p.y, p.z);
        let mut s = format!(
            "v\nfrom {}\nat {}\nup {}\nangle {}\nhither {}\nresolution {} {}\n",
            v(c.from),
            v(c.at),
            v(c.up),
            c.angle,
            c.hither,
            c.width,
            c.height
        );
        if c.aperture > 0.0 {
            s.push_str(&format!("aperture {}\n", c.aperture));
            if let Some(f) = c.focal {
                s.push_str(&format!("focal {f}\n"));
            }
        }
        s
    }

    fn world_up(&self) -> Vec3 {
        self.camera.up.normalize_or(Vec3::Z)
    }

    fn distance(&self) -> f32 {
        (self.camera.from - self.camera.at).length().max(1e-6)
    }

    fn forward(&self) -> Vec3 {
        self.basis().0
    }

    /// Forward, right and up of the view: the ray tracer's.
    fn basis(&self) -> (Vec3, Vec3, Vec3) {
        frame::camera_basis(&self.camera)
    }

    /// Moves the eye and the focus by the same vector.
    fn translate(&mut self, by: Vec3) {
        self.camera.from += by;
        self.camera.at += by;
    }

    fn set_angle(&mut self, angle: f32) {
        self.camera.angle = angle.clamp(1.0, 170.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> OrbitCamera {
        OrbitCamera::new(Camera {
            from: Vec3::new(2.1, 1.3, 1.7),
            at: Vec3::new(0.0, 0.0, 0.1),
            up: Vec3::Z,
            angle: 45.0,
            hither: 0.01,
            width: 400,
            height: 300,
            aperture: 0.0,
            focal: None,
            fit: None,
        })
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4 * (1.0 + a.length())
    }

    #[test]
    fn orbiting_a_full_turn_returns_to_the_start() {
        let mut c = start();
        let from = c.camera.from;
        for _ in 0..36 {
            c.orbit(10.0, 0.0);
        }
        assert!(close(c.camera.from, from), "{} vs {from}", c.camera.from);
        // The same by dragging: 360 degrees of yaw is two image heights of drag.
        for _ in 0..8 {
            c.apply(Input::Drag {
                mode: DragMode::Orbit,
                dx: 75.0,
                dy: 0.0,
            });
        }
        assert!(close(c.camera.from, from), "{} vs {from}", c.camera.from);
        assert_eq!(c.camera.at, start().camera.at);
    }

    #[test]
    fn pitch_stops_short_of_the_poles_and_never_flips_up() {
        let mut c = start();
        let d = (c.camera.from - c.camera.at).length();
        for pitch in [30.0, 60.0, 90.0, 170.0, -400.0, 1000.0] {
            c.orbit(0.0, pitch);
            let (forward, right, up) = c.basis();
            // The camera's up keeps pointing up, and the view never reaches the pole.
            assert!(up.dot(Vec3::Z) > 0.0, "pitch {pitch}: up {up}");
            let polar = (c.camera.from - c.camera.at)
                .angle_between(Vec3::Z)
                .to_degrees();
            assert!((POLE_MARGIN_DEG - 1e-3..=180.0 - POLE_MARGIN_DEG + 1e-3).contains(&polar));
            assert!(right.is_finite() && forward.is_finite());
            assert!(((c.camera.from - c.camera.at).length() - d).abs() < 1e-4 * d);
        }
    }

    #[test]
    fn pitch_turns_about_the_camera_right_axis_not_world_x() {
        let mut c = start();
        let (_, right, _) = c.basis();
        let before = c.camera.from - c.camera.at;
        c.orbit(0.0, 20.0);
        let after = c.camera.from - c.camera.at;
        // Rotating about `right` leaves the component along it unchanged.
        assert!((before.dot(right) - after.dot(right)).abs() < 1e-5);
        assert!((before.angle_between(after).to_degrees() - 20.0).abs() < 1e-2);
    }

    #[test]
    fn a_pan_moves_focus_and_eye_by_the_same_vector() {
        let mut c = start();
        let (from, at) = (c.camera.from, c.camera.at);
        assert!(c.apply(Input::Drag {
            mode: DragMode::Pan,
            dx: 30.0,
            dy: -12.0,
        }));
        let moved = c.camera.at - at;
        assert!(moved.length() > 0.0);
        assert!(close(c.camera.from - from, moved));
    }

    #[test]
    fn wheel_dollies_towards_the_focus_and_reset_restores_the_scene_camera() {
        let mut c = start();
        let d = c.distance();
        c.apply(Input::Wheel(1.0));
        assert!((c.distance() - d * 0.9).abs() < 1e-4);
        assert!(close(c.forward(), start().forward()));
        c.apply(Input::Key(Key::ZoomIn));
        c.apply(Input::Key(Key::Forward));
        assert!(c.apply(Input::Key(Key::Reset)));
        assert_eq!(c.camera, start().camera);
    }

    #[test]
    fn the_printed_view_parses_back_to_the_same_camera() {
        let mut c = start();
        c.orbit(33.0, 12.0);
        let text = c.nff_view();
        let parsed =
            crate::scene::nff::parse(text.as_bytes(), "view", std::path::Path::new(".")).unwrap();
        assert_eq!(parsed.camera, c.camera);
    }
}
