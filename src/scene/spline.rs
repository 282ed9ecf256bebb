//! BART's keyframe curves: Kochanek-Bartels splines through positions (translation and
//! scale keys) and through rotations (as quaternions, by squad), and the on/off
//! visibility keys. The formulas are BART's own (`kbsplpos.c`, `kbsplrot.c` and `quat.c`
//! of its reference code, after Eberly), in double precision, so that an object is where
//! BART's previewer puts it: each segment between keys `i` and `i + 1` gets its tangents
//! from the keys either side, so the first and the last key only shape the curve, and a
//! time outside `[key 1, key n-2]` is held to that range.

use glam::{DQuat, DVec3};

/// The tension, continuity and bias a key gives the curve where it passes through it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tcb {
    pub tension: f64,
    pub continuity: f64,
    pub bias: f64,
}

impl Tcb {
    /// The two weights of a key's outgoing tangent: on the segment before it and on the
    /// one after it (Kochanek and Bartels' `(1-t)(1+c)(1+b)/2` and `(1-t)(1-c)(1-b)/2`),
    /// scaled by `adjust` for uneven spacing in time.
    fn outgoing(&self, adjust: f64) -> (f64, f64) {
        let (t, c, b) = (self.tension, self.continuity, self.bias);
        (
            0.5 * adjust * (1.0 - t) * (1.0 + c) * (1.0 + b),
            0.5 * adjust * (1.0 - t) * (1.0 - c) * (1.0 - b),
        )
    }

    /// The two weights of a key's incoming tangent, likewise.
    fn incoming(&self, adjust: f64) -> (f64, f64) {
        let (t, c, b) = (self.tension, self.continuity, self.bias);
        (
            0.5 * adjust * (1.0 - t) * (1.0 - c) * (1.0 + b),
            0.5 * adjust * (1.0 - t) * (1.0 + c) * (1.0 - b),
        )
    }
}

/// A key of a position curve: at `time`, the curve passes through `value`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionKey {
    pub time: f64,
    pub value: DVec3,
    pub tcb: Tcb,
}

/// A key of a rotation curve: at `time`, a rotation of `angle` radians about `axis`
/// (a unit vector).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationKey {
    pub time: f64,
    pub axis: DVec3,
    pub angle: f64,
    pub tcb: Tcb,
}

/// The fewest keys a curve may have: one each side of the segments it spans.
pub const MIN_KEYS: usize = 4;

/// BART's adjustment of a key's tangent for keys unevenly spaced in time: twice the
/// segment's length in time over the span of the keys either side of the key (for the
/// outgoing tangent of key 1, `2 (t2 - t1) / (t2 - t0)`; for the incoming tangent of key
/// 2, `2 (t2 - t1) / (t3 - t1)`). 1 (none) where that span is empty, which would
/// otherwise divide by zero.
fn adjust(segment: f64, span: f64) -> f64 {
    if span > 0.0 {
        2.0 * segment / span
    } else {
        1.0
    }
}

/// The adjustments of a segment's outgoing and incoming tangents, from its four keys'
/// times.
fn adjustments(t: [f64; 4]) -> (f64, f64) {
    let segment = t[2] - t[1];
    (adjust(segment, t[2] - t[0]), adjust(segment, t[3] - t[1]))
}

/// The segment a time falls in and where in it, from 0 to 1: the first segment whose end
/// is past `t`, held to the curve's span.
fn locate(spans: impl ExactSizeIterator<Item = (f64, f64)> + Clone, t: f64) -> (usize, f64) {
    let n = spans.len();
    let first = spans.clone().next().expect("a curve has a segment").0;
    let last = spans.clone().last().expect("a curve has a segment").1;
    if t <= first {
        return (0, 0.0);
    }
    if t >= last {
        return (n - 1, 1.0);
    }
    let (i, (t0, t1)) = spans
        .enumerate()
        .find(|(_, (_, end))| t < *end)
        .expect("t is before the last segment's end");
    (i, (t - t0) / (t1 - t0))
}

/// A cubic segment `c0 + c1 u + c2 u^2 + c3 u^3` over `u` from 0 to 1, spanning keys
/// `start..end` in time.
#[derive(Clone, Debug, PartialEq)]
struct Cubic {
    start: f64,
    end: f64,
    c: [DVec3; 4],
}

/// A Kochanek-Bartels spline through positions (a translation, or a scale).
#[derive(Clone, Debug, PartialEq)]
pub struct PositionSpline {
    segments: Vec<Cubic>,
}

impl PositionSpline {
    /// The spline through `keys` (at least `MIN_KEYS`, in order of time).
    pub fn new(keys: &[PositionKey]) -> PositionSpline {
        assert!(keys.len() >= MIN_KEYS, "checked by the reader");
        let segments = keys
            .windows(4)
            .map(|k| {
                let (p0, p1, p2, p3) = (k[0].value, k[1].value, k[2].value, k[3].value);
                let d = p2 - p1;
                let (adj_out, adj_in) = adjustments([k[0].time, k[1].time, k[2].time, k[3].time]);
                let (out0, out1) = k[1].tcb.outgoing(adj_out);
                let tout = out1 * d + out0 * (p1 - p0);
                let (in0, in1) = k[2].tcb.incoming(adj_in);
                let tin = in1 * (p3 - p2) + in0 * d;
                Cubic {
                    start: k[1].time,
                    end: k[2].time,
                    c: [p1, tout, 3.0 * d - 2.0 * tout - tin, -2.0 * d + tout + tin],
                }
            })
            .collect();
        PositionSpline { segments }
    }

    /// The position at time `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        let (i, u) = locate(self.segments.iter().map(|s| (s.start, s.end)), t);
        let c = &self.segments[i].c;
        c[0] + u * (c[1] + u * (c[2] + u * c[3]))
    }
}

/// A segment of a rotation curve: squad from `p` to `q` with inner controls `a`, `b`.
#[derive(Clone, Debug, PartialEq)]
struct Squad {
    start: f64,
    end: f64,
    p: DQuat,
    a: DQuat,
    b: DQuat,
    q: DQuat,
}

/// A Kochanek-Bartels spline through rotations, interpolated by squad.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationSpline {
    segments: Vec<Squad>,
}

impl RotationSpline {
    /// The spline through `keys` (at least `MIN_KEYS`, in order of time).
    pub fn new(keys: &[RotationKey]) -> RotationSpline {
        assert!(keys.len() >= MIN_KEYS, "checked by the reader");
        let mut quats: Vec<DQuat> = keys
            .iter()
            .map(|k| DQuat::from_axis_angle(k.axis, k.angle))
            .collect();
        let mut segments = Vec::with_capacity(keys.len() - 3);
        for i in 0..keys.len() - 3 {
            let k = &keys[i..i + 4];
            // Consecutive keys take the nearer of q and -q (the same rotation), so that
            // the curve turns the short way; BART flips the later key for good, so the
            // next segment starts from the flipped one.
            if quats[i + 1].dot(quats[i + 2]) < 0.0 {
                quats[i + 2] = -quats[i + 2];
            }
            let (q0, q1, q2, q3) = (quats[i], quats[i + 1], quats[i + 2], quats[i + 3]);
            let logdq = log(q1.conjugate() * q2);
            let (adj_out, adj_in) = adjustments([k[0].time, k[1].time, k[2].time, k[3].time]);
            let (out0, out1) = k[1].tcb.outgoing(adj_out);
            let tout = out1 * logdq + out0 * log(q0.conjugate() * q1);
            let (in0, in1) = k[2].tcb.incoming(adj_in);
            let tin = in0 * logdq + in1 * log(q2.conjugate() * q3);
            segments.push(Squad {
                start: k[1].time,
                end: k[2].time,
                p: q1,
                a: q1 * exp(0.5 * (tout - logdq)),
                b: q2 * exp(0.5 * (logdq - tin)),
                q: q2,
            });
        }
        RotationSpline { segments }
    }

    /// The rotation at time `t`.
    pub fn at(&self, t: f64) -> DQuat {
        let (i, s) = locate(self.segments.iter().map(|s| (s.start, s.end)), t);
        let g = &self.segments[i];
        slerp(2.0 * s * (1.0 - s), slerp(s, g.p, g.q), slerp(s, g.a, g.b))
    }
}

/// Below this, a sine is taken as zero (BART's `g_dEpsilon`).
const EPSILON: f64 = 1e-6;

/// The logarithm of a unit quaternion, as a pure quaternion `A (x, y, z)` held in a
/// vector.
fn log(q: DQuat) -> DVec3 {
    let v = DVec3::new(q.x, q.y, q.z);
    if q.w.abs() < 1.0 {
        let angle = q.w.acos();
        let sn = angle.sin();
        if sn.abs() >= EPSILON {
            return v * (angle / sn);
        }
    }
    v
}

/// The exponential of the pure quaternion `v`.
fn exp(v: DVec3) -> DQuat {
    let angle = v.length();
    let sn = angle.sin();
    let v = if sn.abs() >= EPSILON {
        v * (sn / angle)
    } else {
        v
    };
    DQuat::from_xyzw(v.x, v.y, v.z, angle.cos())
}

/// Spherical interpolation from `p` (at 0) to `q` (at 1), as BART does it: no turn to
/// the nearer of `q` and `-q` (the keys were arranged for that already), and `p` where
/// the two are too close for the sine to be trusted.
fn slerp(t: f64, p: DQuat, q: DQuat) -> DQuat {
    let cos = p.dot(q).clamp(-1.0, 1.0);
    let angle = cos.acos();
    let sn = angle.sin();
    if sn < EPSILON {
        return p;
    }
    let c0 = ((1.0 - t) * angle).sin() / sn;
    let c1 = (t * angle).sin() / sn;
    DQuat::from_xyzw(
        c0 * p.x + c1 * q.x,
        c0 * p.y + c1 * q.y,
        c0 * p.z + c1 * q.z,
        c0 * p.w + c1 * q.w,
    )
}

/// A visibility key: from `time` on, the object is shown or not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityKey {
    pub time: f64,
    pub visible: bool,
}

/// Whether an object with these keys (in order of time) is shown at time `t`: shown
/// before the first key, then as the last key at or before `t` says.
pub fn visible(keys: &[VisibilityKey], t: f64) -> bool {
    keys.iter()
        .take_while(|k| k.time <= t)
        .last()
        .is_none_or(|k| k.visible)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f64, x: f64) -> PositionKey {
        PositionKey {
            time,
            value: DVec3::new(x, 2.0 * x, 0.0),
            tcb: Tcb::default(),
        }
    }

    /// At its keys the curve passes through them; between them, with tension, continuity
    /// and bias zero and keys evenly spaced, it is the Catmull-Rom spline, whose value at
    /// the middle of a segment is `(-p0 + 9 p1 + 9 p2 - p3) / 16`.
    #[test]
    fn a_position_curve_is_catmull_rom_at_zero_tcb() {
        let keys = [key(-1.0, 0.0), key(0.0, 1.0), key(1.0, 5.0), key(2.0, 2.0)];
        let s = PositionSpline::new(&keys);
        assert_eq!(s.at(0.0), keys[1].value);
        assert_eq!(s.at(1.0), keys[2].value);
        let mid = (-0.0 + 9.0 * 1.0 + 9.0 * 5.0 - 2.0) / 16.0;
        assert!((s.at(0.5).x - mid).abs() < 1e-12, "{}", s.at(0.5).x);
        // Held to the span of the inner keys.
        assert_eq!(s.at(-5.0), keys[1].value);
        assert_eq!(s.at(9.0), keys[2].value);
    }

    /// Tension 1 makes both tangents zero: the segment eases in and out, the smoothstep
    /// `3u^2 - 2u^3` between its keys.
    #[test]
    fn full_tension_eases_between_keys() {
        let mut keys = [key(-1.0, 7.0), key(0.0, 1.0), key(1.0, 3.0), key(2.0, -4.0)];
        for k in &mut keys {
            k.tcb.tension = 1.0;
        }
        let s = PositionSpline::new(&keys);
        let u: f64 = 0.25;
        let want = 1.0 + 2.0 * (3.0 * u * u - 2.0 * u * u * u);
        assert!((s.at(u).x - want).abs() < 1e-12);
    }

    fn rot(time: f64, deg: f64) -> RotationKey {
        RotationKey {
            time,
            axis: DVec3::Z,
            angle: deg.to_radians(),
            tcb: Tcb::default(),
        }
    }

    /// About one axis, squad with zero tcb and even keys turns as the Catmull-Rom curve of
    /// the angles does (the logarithms of the quaternions are half-angles on one line).
    #[test]
    fn a_rotation_about_one_axis_follows_its_angles() {
        let keys = [
            rot(0.0, 0.0),
            rot(1.0, 10.0),
            rot(2.0, 40.0),
            rot(3.0, 50.0),
        ];
        let s = RotationSpline::new(&keys);
        let angle = |q: DQuat| q.to_axis_angle().1.to_degrees();
        assert!((angle(s.at(1.0)) - 10.0).abs() < 1e-9);
        assert!((angle(s.at(2.0)) - 40.0).abs() < 1e-9);
        let (axis, _) = s.at(1.5).to_axis_angle();
        assert!((axis - DVec3::Z).length() < 1e-9);
        let catmull_rom = (-0.0 + 9.0 * 10.0 + 9.0 * 40.0 - 50.0) / 16.0;
        assert!(
            (angle(s.at(1.5)) - catmull_rom).abs() < 1e-6,
            "{}",
            angle(s.at(1.5))
        );
    }

    #[test]
    fn visibility_switches_at_its_keys() {
        let keys = [
            VisibilityKey {
                time: 0.5,
                visible: false,
            },
            VisibilityKey {
                time: 2.0,
                visible: true,
            },
        ];
        assert!(visible(&keys, 0.0));
        assert!(!visible(&keys, 0.5));
        assert!(!visible(&keys, 1.9));
        assert!(visible(&keys, 2.0));
        assert!(visible(&[], 1.0));
    }
}
