//! Which reader a file is for, told by its first bytes as well as its name: a PLY or glTF
//! file is read as one whatever its name, and a file in a format gpurt does not read (an
//! image, an archive, FBX, ...) is named as what it is, rather than read as NFF and refused
//! with a message about NFF keywords.

use std::io::Read;
use std::path::Path;

use super::io::{FileKind, Input, read_error};
use crate::util::error::{Error, Result};

/// What gpurt reads, for messages about what it does not.
pub const READS: &str = "gpurt reads NFF, STL, OBJ, PLY and glTF";

const JSON: &str = "a JSON file";

/// Bytes looked at: enough for a JSON file's `"asset"` key to show.
const HEAD: usize = 512;

/// `input`, whose name is `name`, with the reader its first bytes call for (`kind`, from
/// its name, when they call for none), its bytes all still to be read.
pub fn sniff<'a>(
    mut input: Input<'a>,
    kind: FileKind,
    name: &str,
) -> Result<(Input<'a>, FileKind)> {
    let mut head = Vec::with_capacity(HEAD);
    (&mut input.reader)
        .take(HEAD as u64)
        .read_to_end(&mut head)
        .map_err(|e| read_error(name, e))?;
    let kind = match told(&head) {
        Some(Told::Reads(k)) => k,
        // glTF's "asset" key may come after the bytes looked at.
        Some(Told::Foreign(JSON)) if kind == FileKind::Gltf => kind,
        Some(Told::Foreign(what)) => return Err(foreign(name, what)),
        None => match by_extension(name) {
            Some(what) => return Err(foreign(name, what)),
            None => kind,
        },
    };
    let reader = Box::new(std::io::Cursor::new(head).chain(input.reader));
    Ok((Input { reader, ..input }, kind))
}

fn foreign(name: &str, what: &str) -> Error {
    Error::Scene {
        file: name.to_string(),
        msg: format!("{what}; {READS}"),
    }
}

enum Told {
    Reads(FileKind),
    Foreign(&'static str),
}

/// What a file's first bytes say it is, where they say it clearly.
fn told(head: &[u8]) -> Option<Told> {
    const MAGIC: [(&[u8], &str); 11] = [
        (b"\x89PNG", "a PNG image"),
        (b"\xff\xd8\xff", "a JPEG image"),
        (b"GIF8", "a GIF image"),
        (b"PK\x03\x04", "a zip archive"),
        (b"Kaydara FBX Binary", "an FBX file"),
        (b"; FBX", "an FBX file"),
        (b"BLENDER", "a Blender file"),
        (b"%PDF", "a PDF document"),
        (b"\x7fELF", "an executable"),
        (b"<?xml", "an XML file"),
        (b"#usda", "a USD file"),
    ];
    if head.starts_with(b"ply\n") || head.starts_with(b"ply\r\n") {
        return Some(Told::Reads(FileKind::Ply));
    }
    if head.starts_with(b"glTF") {
        return Some(Told::Reads(FileKind::Gltf));
    }
    if let Some((_, what)) = MAGIC.iter().find(|(m, _)| head.starts_with(m)) {
        return Some(Told::Foreign(what));
    }
    let text = head.trim_ascii_start();
    if text.starts_with(b"{") {
        let gltf = text.windows(7).any(|w| w == b"\"asset\"");
        return Some(if gltf {
            Told::Reads(FileKind::Gltf)
        } else {
            Told::Foreign(JSON)
        });
    }
    None
}

/// What a name's extension says a file is, for the formats gpurt does not read.
fn by_extension(name: &str) -> Option<&'static str> {
    let name = name.to_ascii_lowercase();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    let ext = Path::new(name).extension()?.to_str()?;
    Some(match ext {
        "fbx" => "an FBX file",
        "3ds" => "a 3DS file",
        "blend" => "a Blender file",
        "dae" => "a COLLADA file",
        "usd" | "usda" | "usdc" | "usdz" => "a USD file",
        "3mf" => "a 3MF file",
        "x3d" | "wrl" => "an X3D or VRML file",
        "abc" => "an Alembic file",
        "png" | "jpg" | "jpeg" | "exr" | "hdr" => "an image",
        _ => return None,
    })
}
