//! `map_Kd`: the image a material's colour is multiplied by, its options read (or warned
//! of and skipped), and the texture it names, read when a face first uses the material.

use std::path::{Path, PathBuf};

use glam::{Affine2, Vec2};

use crate::scene::images;
use crate::scene::io;
use crate::scene::lex::{Lexer, Token};
use crate::scene::model::Wrap;
use crate::scene::sink::MeshOut;
use crate::util::error::Result;
use crate::util::limits::MAX_IMAGE_BYTES;

/// A `map_Kd` statement: the image and how it lies on the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct MapKd {
    /// The path as written, after the options, relative to `dir`.
    pub path: String,
    /// The library's folder (`None` for a library that is not a file).
    pub dir: Option<PathBuf>,
    /// `-clamp on`: clamped to the edge, else repeated.
    pub wrap: Wrap,
    /// `-s` and `-o`: the texture coordinates scaled, then offset.
    pub uv: Affine2,
    /// Where it is written (`FILE:LINE:COL`), for its warnings.
    pub at: String,
}

/// `map_Kd [OPTIONS] FILE` after its keyword `t`, in a library in folder `dir`. Of the
/// options, `-s`, `-o` (the texture coordinates scaled, then offset) and `-clamp` are
/// read; the others are skipped with their values and a warning each per file. A name
/// may hold spaces.
pub fn map_kd(
    lx: &mut Lexer,
    t: &Token,
    dir: Option<&Path>,
    warnings: &mut Vec<String>,
    skipped: &mut Vec<String>,
) -> Result<Option<MapKd>> {
    let line = t.line;
    let (mut scale, mut offset, mut wrap) = (Vec2::ONE, Vec2::ZERO, Wrap::Repeat);
    while let Some(o) = lx.peek()?.filter(|o| o.line == line) {
        let option = String::from_utf8_lossy(lx.text(&o)).into_owned();
        // The values each option takes; `-s`, `-o` and `-t` take one to three numbers.
        let values = match option.as_str() {
            "-s" | "-o" | "-t" => 3,
            "-mm" => 2,
            "-blendu" | "-blendv" | "-boost" | "-texres" | "-clamp" | "-bm" | "-imfchan"
            | "-cc" | "-type" => 1,
            _ => break,
        };
        lx.next_token()?;
        let numbers = values == 3;
        let mut args = Vec::new();
        while args.len() < values {
            let Some(a) = lx.peek()?.filter(|a| a.line == line) else {
                break;
            };
            let arg = String::from_utf8_lossy(lx.text(&a)).into_owned();
            let number = arg.parse::<f32>().ok().filter(|x| x.is_finite());
            if numbers && number.is_none() {
                break;
            }
            lx.next_token()?;
            args.push((arg, number.unwrap_or(0.0)));
        }
        let uv = |default: Vec2| {
            Vec2::new(
                args.first().map_or(default.x, |a| a.1),
                args.get(1).map_or(default.y, |a| a.1),
            )
        };
        match option.as_str() {
            "-s" => scale = uv(Vec2::ONE),
            "-o" => offset = uv(Vec2::ZERO),
            "-clamp" => {
                wrap = if args.first().is_some_and(|a| a.0 == "on") {
                    Wrap::Clamp
                } else {
                    Wrap::Repeat
                }
            }
            _ => {
                let key = format!("map_Kd {option}");
                if !skipped.contains(&key) {
                    warnings.push(format!(
                        "{}:{}:{}: map_Kd's option '{option}' is not read; skipped here and below",
                        lx.name(),
                        o.line,
                        o.col
                    ));
                    skipped.push(key);
                }
            }
        }
    }
    let path = lx.rest_of_line(line)?;
    if path.is_empty() {
        warnings.push(format!(
            "{}:{}:{}: map_Kd names no image; skipped",
            lx.name(),
            t.line,
            t.col
        ));
        return Ok(None);
    }
    Ok(Some(MapKd {
        path,
        dir: dir.map(Path::to_path_buf),
        wrap,
        uv: Affine2::from_scale_angle_translation(scale, 0.0, offset),
        at: format!("{}:{}:{}", lx.name(), t.line, t.col),
    }))
}

/// The texture of `map`, read the first time a material names it (and shared after), or
/// why it cannot be had.
pub fn texture(map: &MapKd, out: &mut MeshOut) -> std::result::Result<u32, String> {
    let dir = map
        .dir
        .as_deref()
        .ok_or("the library was not read from a file")?;
    // Libraries written on Windows separate folders with backslashes.
    let rel = if map.path.contains('\\') && !dir.join(&map.path).exists() {
        map.path.replace('\\', "/")
    } else {
        map.path.clone()
    };
    let wrap = [map.wrap; 2];
    let name = dir.join(&rel).display().to_string();
    if let Some(i) = images::find(out.textures, &name, wrap) {
        return Ok(i);
    }
    let bytes = io::read_inside(dir, &rel, MAX_IMAGE_BYTES)?;
    let texture = images::decode(&bytes, &name, wrap)?;
    Ok(images::add(out.textures, texture, out.warnings))
}

#[cfg(test)]
mod tests {
    use super::super::tests::library;
    use super::*;

    #[test]
    fn map_kd_reads_its_options_and_names_with_spaces() {
        let (lib, warnings) = library(
            "newmtl a\nmap_Kd -s 2 3 1 -o 0.5 -clamp on -bm 0.2 -mm 0 1 my wood.png\n\
             newmtl b\nmap_Kd -s 4 -bm 1 b.png\nmap_Ks s.png\nnewmtl c\nmap_Kd -o 1\n",
        );
        let a = lib["a"].map_kd.as_ref().unwrap();
        assert_eq!((a.path.as_str(), a.wrap), ("my wood.png", Wrap::Clamp));
        let uv = a.uv.transform_point2(Vec2::new(1.0, 1.0));
        assert_eq!(uv, Vec2::new(2.5, 3.0));
        let b = lib["b"].map_kd.as_ref().unwrap();
        assert_eq!(b.path, "b.png");
        assert_eq!(b.uv.transform_point2(Vec2::ONE), Vec2::new(4.0, 1.0));
        assert!(lib["c"].map_kd.is_none());
        let want = [
            "m.mtl:2:34: map_Kd's option '-bm' is not read",
            "m.mtl:2:42: map_Kd's option '-mm' is not read",
            "m.mtl:5:1: 'map_Ks' is not read",
            "m.mtl:7:1: map_Kd names no image",
        ];
        assert_eq!(warnings.len(), want.len(), "{warnings:?}");
        for (w, want) in warnings.iter().zip(want) {
            assert!(w.starts_with(want), "{w}");
        }
    }
}
