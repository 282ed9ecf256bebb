//! The shading options renders and the viewer both take, defined once: the ambient light,
//! the seed of the sample hash and the highlight's model.

use glam::Vec3;
use gpurt::frame::Shading;
use gpurt::util::limits::DEFAULT_AMBIENT;

use super::values::{parse_colour, shadings};

#[derive(clap::Args)]
pub struct ShadeArgs {
    #[arg(long, value_parser = parse_colour, help = format!(
        "Ambient light: one grey level or r,g,b (default: the scene's `am`, else {DEFAULT_AMBIENT})"
    ))]
    pub ambient: Option<Vec3>,
    /// Seed of the sample hash.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Model of the specular highlight; everything else is shaded alike.
    #[arg(long, default_value = "phong", value_parser = shadings())]
    pub shading: Shading,
}
