//! AFF's keyframes (`k name { transl | rot | scale N ... visibility N ... }`): each
//! curve's keys read and checked (at least 4 for a spline, in order of time, a rotation
//! about an axis) into the track of its name. The curves themselves are `spline`'s.

use glam::DVec3;

use super::Parser;
use crate::scene::animation::Track;
use crate::scene::lex::Token;
use crate::scene::spline::{
    MIN_KEYS, PositionKey, PositionSpline, RotationKey, RotationSpline, Tcb, VisibilityKey,
};
use crate::util::error::{Result, escape};

/// A keyframe's time as read, and its token (for the message if it is out of order).
struct Timed {
    time: f64,
    tok: Token,
}

impl Parser<'_> {
    /// `k name { transl N ... rot N ... scale N ... visibility N ... }`.
    pub(super) fn keyframes(&mut self, tok: &Token) -> Result<()> {
        let (name, _) = self.name("name of the transform the keyframes animate")?;
        let i = self.blocks.name(&name, None);
        self.expect_open_brace("keyframes")?;
        let mut track = Track {
            name,
            ..Track::default()
        };
        loop {
            let t = self
                .lx
                .expect_token("keyframes ('transl', 'rot', 'scale', 'visibility') or '}'")?;
            let kind = String::from_utf8_lossy(self.lx.text(&t)).into_owned();
            let twice = match kind.as_str() {
                "}" => break,
                "transl" => track.translation.is_some(),
                "rot" => track.rotation.is_some(),
                "scale" => track.scale.is_some(),
                "visibility" => !track.visibility.is_empty(),
                _ => {
                    return Err(self.lx.error_at(
                        &t,
                        format!(
                            "expected keyframes ('transl', 'rot', 'scale' or 'visibility') or '}}', found {}",
                            self.lx.show(&t)
                        ),
                    ));
                }
            };
            if twice {
                return Err(self
                    .lx
                    .error_at(&t, format!("a second '{kind}' in one 'k' block")));
            }
            let (n, ntok) = self.lx.count(&format!("number of {kind} keys"))?;
            let least = if kind == "visibility" {
                1
            } else {
                MIN_KEYS as u32
            };
            if n < least {
                let why = if least > 1 {
                    " (the first and the last only shape the curve)"
                } else {
                    ""
                };
                return Err(self.lx.error_at(
                    &ntok,
                    format!("'{kind}' needs at least {least} keys{why}, found {n}"),
                ));
            }
            self.check_count(&ntok, n, if kind == "rot" { 16 } else { 8 })?;
            // Keys left out (`key_time`) may leave too few for a curve.
            let few = |p: &Self, kept: usize| {
                p.lx.error_at(
                    &ntok,
                    format!("'{kind}' keeps {kept} keys in order of time, fewer than the {least} it needs"),
                )
            };
            match kind.as_str() {
                "transl" | "scale" => {
                    let what = if kind == "transl" {
                        "translation"
                    } else {
                        "scale"
                    };
                    let keys = self.position_keys(n, what)?;
                    if keys.len() < MIN_KEYS {
                        return Err(few(self, keys.len()));
                    }
                    let spline = Some(PositionSpline::new(&keys));
                    match kind.as_str() {
                        "transl" => track.translation = spline,
                        _ => track.scale = spline,
                    }
                }
                "rot" => {
                    let keys = self.rotation_keys(n)?;
                    if keys.len() < MIN_KEYS {
                        return Err(few(self, keys.len()));
                    }
                    track.rotation = Some(RotationSpline::new(&keys));
                }
                _ => track.visibility = self.visibility_keys(n)?,
            }
        }
        // A second `k` for a name (a file included twice holds its keyframes twice): the
        // first is used, as BART's `FindAnimation` does, and other keys are warned of.
        match &self.blocks.names[i].track {
            None => self.blocks.names[i].track = Some(track),
            Some(first) if *first == track => {}
            Some(_) => {
                let msg = format!(
                    "a second 'k {}' with other keys; the first is used",
                    escape(track.name.as_bytes())
                );
                self.warn(tok, &msg);
            }
        }
        Ok(())
    }

    /// A key's time, and whether the key is kept: a key before the last one kept is an
    /// error, or with `--lenient` left out with a warning (BART's robots have keys that
    /// go back in time, which its previewer never reaches).
    fn key_time(&mut self, last: Option<&Timed>) -> Result<(Timed, bool)> {
        let tok = self.lx.peek()?;
        let time = f64::from(self.lx.number("keyframe time")?);
        let tok = tok.expect("a number was read");
        let timed = Timed { time, tok };
        let Some(last) = last.filter(|last| time < last.time) else {
            return Ok((timed, true));
        };
        let msg = format!(
            "keyframe time {time} is before the previous key's {} (line {}): keys go in order of time",
            last.time, last.tok.line
        );
        if !self.lenient {
            return Err(self.lx.error_at(&tok, msg));
        }
        self.warn(
            &tok,
            &format!("{msg}; left out, with the keys after it that go back"),
        );
        Ok((timed, false))
    }

    fn tcb(&mut self) -> Result<Tcb> {
        Ok(Tcb {
            tension: f64::from(self.lx.number("keyframe tension")?),
            continuity: f64::from(self.lx.number("keyframe continuity")?),
            bias: f64::from(self.lx.number("keyframe bias")?),
        })
    }

    /// `n` keys, each its time then what `read` reads of it; the keys `key_time` leaves
    /// out are read and dropped.
    fn keys<K>(
        &mut self,
        n: u32,
        mut read: impl FnMut(&mut Self, &Timed) -> Result<K>,
    ) -> Result<Vec<K>> {
        let mut keys = Vec::with_capacity(n as usize);
        let mut last = None;
        for _ in 0..n {
            let (timed, keep) = self.key_time(last.as_ref())?;
            let key = read(self, &timed)?;
            if keep {
                keys.push(key);
                last = Some(timed);
            }
        }
        Ok(keys)
    }

    fn position_keys(&mut self, n: u32, what: &str) -> Result<Vec<PositionKey>> {
        self.keys(n, |p, timed| {
            Ok(PositionKey {
                time: timed.time,
                value: p.lx.vec3(&format!("{what} key"))?.as_dvec3(),
                tcb: p.tcb()?,
            })
        })
    }

    fn rotation_keys(&mut self, n: u32) -> Result<Vec<RotationKey>> {
        self.keys(n, |p, timed| {
            let axis = p.lx.vec3("rotation key axis")?.as_dvec3();
            let deg = f64::from(p.lx.number("rotation key angle in degrees")?);
            // A zero angle turns about any axis (BART writes `0 0 0 0` for none).
            let axis = match axis.try_normalize() {
                Some(a) => a,
                None if deg == 0.0 => DVec3::X,
                None => {
                    return Err(p.lx.error_at(
                        &timed.tok,
                        format!("a rotation key of {deg} degrees about a zero axis"),
                    ));
                }
            };
            Ok(RotationKey {
                time: timed.time,
                axis,
                angle: deg.to_radians(),
                tcb: p.tcb()?,
            })
        })
    }

    fn visibility_keys(&mut self, n: u32) -> Result<Vec<VisibilityKey>> {
        self.keys(n, |p, timed| {
            let (flag, ftok) = p.lx.count("visibility flag (0 or 1)")?;
            if flag > 1 {
                return Err(p.lx.error_at(
                    &ftok,
                    format!("expected a visibility flag of 0 or 1, found {flag}"),
                ));
            }
            Ok(VisibilityKey {
                time: timed.time,
                visible: flag == 1,
            })
        })
    }
}
