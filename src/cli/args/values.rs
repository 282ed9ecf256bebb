//! The value parsers the commands' flags share: sizes, colours, limits, and the
//! backends and shading models each command accepts, with their `--help` lines.

use glam::Vec3;
use gpurt::frame::Shading;
use gpurt::session::Backend;
use gpurt::util::limits::MAX_IMAGE_SIDE;

pub(super) fn parse_colour(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("'{p}': {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [g] if g.is_finite() && g >= 0.0 => Ok(Vec3::splat(g)),
        [r, g, b] if [r, g, b].iter().all(|c| c.is_finite() && *c >= 0.0) => Ok(Vec3::new(r, g, b)),
        _ => Err("expected one non-negative number or three separated by commas".into()),
    }
}

/// A threshold: a finite number, not negative (NaN would make every comparison pass).
pub(super) fn parse_limit(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}': expected a finite number, 0 or more")),
    }
}

/// `--backend`'s parser for a command: the backends it accepts, in order, each with the
/// line `--help` shows for it.
pub(super) fn backends(
    accepted: &[(Backend, Option<&'static str>)],
) -> impl clap::builder::TypedValueParser<Value = Backend> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let values = accepted.iter().map(|&(backend, help)| {
        let value = PossibleValue::new(backend.name());
        match help {
            Some(help) => value.help(help),
            None => value,
        }
    });
    PossibleValuesParser::new(values)
        .map(|name| Backend::from_name(&name).expect("a backend's name"))
}

/// `--shading`'s parser: every model by its name, with the line `--help` shows for it.
pub(super) fn shadings() -> impl clap::builder::TypedValueParser<Value = Shading> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Shading::ALL.map(|s| {
        PossibleValue::new(s.name()).help(match s {
            Shading::Phong => "Ks (R.L)^Shine, R the mirrored ray: NFF's model",
            Shading::BlinnPhong => {
                "Ks (N.H)^Shine, H halfway between the light and the viewer: the P3D course's"
            }
        })
    }))
    .map(|name| Shading::from_name(&name).expect("a shading model's name"))
}

pub(super) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT"))?;
    let dim = |d: &str| match d.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_IMAGE_SIDE).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': each side must be 1 to {MAX_IMAGE_SIDE}")),
    };
    Ok((dim(w)?, dim(h)?))
}
