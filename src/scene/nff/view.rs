//! The NFF `v` block: the camera (`from`, `at`, `up`, `angle`, `hither`, `resolution`,
//! and our `aperture` and `focal`), checked for what would make no image. Apart from the
//! statement loop because it is a small grammar of its own.

use super::keywords::{STATEMENTS, VIEW_KEYWORDS, closest};
use super::{Parser, keyword};
use crate::scene::lex::{Token, parse_f32};
use crate::scene::model::nff_default_camera;
use crate::util::error::Result;
use crate::util::limits::MAX_IMAGE_SIDE;

impl Parser<'_> {
    pub(super) fn view(&mut self, vtok: &Token) -> Result<()> {
        let mut cam = nff_default_camera();
        let (mut from, mut at, mut up, mut angle) = (None, None, None, None);
        let mut resolution = None;
        while let Some(t) = self.lx.peek()? {
            let (word, len) = keyword(self.lx.text(&t));
            if !VIEW_KEYWORDS.iter().any(|k| k.as_bytes() == &word[..len]) {
                // The view ends at the next statement; a word that is neither a statement
                // nor a number, where the view still lacks a keyword or is close to one
                // (`angel 40`), is a mistyped view keyword, named where it stands.
                let text = self.lx.text(&t);
                let required_missing =
                    [&from, &at, &up].iter().any(|v| v.is_none()) || angle.is_none();
                let statement = STATEMENTS.iter().any(|k| k.as_bytes() == text);
                let meant = closest(text, &VIEW_KEYWORDS);
                if !statement && parse_f32(text).is_none() && (required_missing || meant.is_some())
                {
                    let hint = meant
                        .map(|k| format!("; did you mean '{k}'?"))
                        .unwrap_or_default();
                    return Err(self.lx.error_at(
                        &t,
                        format!(
                            "expected a view keyword ({}), found {}{hint}",
                            VIEW_KEYWORDS.join(", "),
                            self.lx.show(&t)
                        ),
                    ));
                }
                break;
            }
            self.lx.next_token()?;
            match &word[..len] {
                b"from" => from = Some(self.lx.vec3("'from' coordinate")?),
                b"at" => at = Some(self.lx.vec3("'at' coordinate")?),
                b"up" => up = Some(self.lx.vec3("'up' coordinate")?),
                b"angle" => {
                    let a = self.lx.peek()?;
                    let v = self.lx.number("view angle in degrees")?;
                    if !(v > 0.0 && v < 180.0) {
                        let a = a.expect("number was read");
                        return Err(self.lx.error_at(
                            &a,
                            format!("expected a view angle in (0, 180) degrees, found {v}"),
                        ));
                    }
                    angle = Some(v);
                }
                b"hither" => {
                    let h = self.lx.number("hither distance")?;
                    cam.hither = h.max(0.0);
                }
                b"resolution" => {
                    let (w, wt) = self.lx.count("resolution width")?;
                    let (h, ht) = self.lx.count("resolution height")?;
                    for count in [(w, wt), (h, ht)] {
                        self.within(count, "a resolution", MAX_IMAGE_SIDE)?;
                    }
                    resolution = Some((w, h));
                }
                b"aperture" => cam.aperture = self.lx.number("lens aperture")?.abs(),
                b"focal" => {
                    let f = self.lx.peek()?;
                    let d = self.lx.number("focal distance")?;
                    if d <= 0.0 {
                        let f = f.expect("number was read");
                        return Err(self.lx.error_at(
                            &f,
                            format!("expected a positive focal distance, found {d}"),
                        ));
                    }
                    cam.focal = Some(d);
                }
                _ => unreachable!(),
            }
        }
        let missing = [
            ("from", from.is_none()),
            ("at", at.is_none()),
            ("up", up.is_none()),
            ("angle", angle.is_none()),
        ];
        if let Some((what, _)) = missing.iter().find(|(_, m)| *m) {
            return Err(self.lx.error_at(
                vtok,
                format!("view is missing '{what}' (from, at, up and angle are required)"),
            ));
        }
        cam.from = from.unwrap();
        cam.at = at.unwrap();
        cam.up = up.unwrap();
        cam.angle = angle.unwrap();
        if let Some((w, h)) = resolution {
            cam.width = w;
            cam.height = h;
        }
        if let Some(problem) = cam.view_problem() {
            return Err(self.lx.error_at(vtok, problem));
        }
        if self.have_view {
            self.warn(vtok, "second view replaces the first");
        }
        self.have_view = true;
        self.scene.camera = cam;
        Ok(())
    }
}
