//! The NFF reader's lights: point lights (`l`, NFF's), and gpurt's directional (`dl`) and
//! area lights (`al`), their colours held to `MAX_LIGHT`.

use glam::Vec3;

use super::Parser;
use crate::scene::lex::Token;
use crate::scene::model::Light;
use crate::util::error::Result;
use crate::util::limits::{MAX_AREA_LIGHT_SAMPLES, MAX_LIGHT};

impl Parser<'_> {
    pub(super) fn point_light(&mut self, tok: &Token) -> Result<()> {
        let position = self.lx.vec3("light position")?;
        let color = self.optional_colour("light colour")?;
        let color = color.map(|c| self.hold3(tok, "light colour", c, MAX_LIGHT));
        self.put_light(Light::Point { position, color });
        Ok(())
    }

    pub(super) fn directional_light(&mut self, tok: &Token) -> Result<()> {
        let direction = self.lx.vec3("light direction")?;
        if direction.length_squared() == 0.0 {
            return Err(self
                .lx
                .error_at(tok, "directional light with a zero direction"));
        }
        let color = self.optional_colour("light colour")?;
        let color = color.map(|c| self.hold3(tok, "light colour", c, MAX_LIGHT));
        self.put_light(Light::Directional {
            direction: direction.normalize(),
            color,
        });
        Ok(())
    }

    pub(super) fn area_light(&mut self, tok: &Token) -> Result<()> {
        let corner = self.lx.vec3("area light corner")?;
        let u = self.lx.vec3("area light edge u")?;
        let v = self.lx.vec3("area light edge v")?;
        let color = self.lx.vec3("area light colour")?;
        let color = self.hold3(tok, "area light colour", color, MAX_LIGHT);
        let (nu, nut) = self.lx.count("area light samples along u")?;
        let (nv, nvt) = self.lx.count("area light samples along v")?;
        for count in [(nu, nut), (nv, nvt)] {
            self.within(count, "area light samples", MAX_AREA_LIGHT_SAMPLES)?;
        }
        if u.cross(v).length_squared() == 0.0 {
            return Err(self
                .lx
                .error_at(tok, "degenerate area light: its edges are parallel or zero"));
        }
        self.put_light(Light::Area {
            corner,
            u,
            v,
            color,
            samples: [nu, nv],
        });
        Ok(())
    }

    /// A colour, where the statement goes on with a number.
    pub(super) fn optional_colour(&mut self, what: &str) -> Result<Option<Vec3>> {
        if self.lx.peek_is_number()? {
            Ok(Some(self.lx.vec3(what)?))
        } else {
            Ok(None)
        }
    }
}
