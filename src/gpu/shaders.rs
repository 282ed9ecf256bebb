//! WGSL assembly: the shader files joined in a fixed order (WGSL allows declarations in
//! any order, so no import system is needed), each behind a banner naming its file.

/// The files, in the order they are joined; each is mirrored by `src/cpu/<name>.rs`.
pub const FILES: [(&str, &str); 5] = [
    ("types.wgsl", include_str!("../../shaders/types.wgsl")),
    (
        "intersect.wgsl",
        include_str!("../../shaders/intersect.wgsl"),
    ),
    ("traverse.wgsl", include_str!("../../shaders/traverse.wgsl")),
    ("shade.wgsl", include_str!("../../shaders/shade.wgsl")),
    ("main.wgsl", include_str!("../../shaders/main.wgsl")),
];

/// The whole shader source.
pub fn source() -> String {
    let mut s = String::new();
    for (name, text) in FILES {
        s.push_str(&format!("// ---- shaders/{name} ----\n"));
        s.push_str(text);
        s.push('\n');
    }
    s
}

/// Parses and validates the joined source with naga, as wgpu will: shader mistakes fail
/// here, without any GPU. Returns the module and its layout information for reflection.
pub fn validate() -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let src = source();
    let module = naga::front::wgsl::parse_str(&src).map_err(|e| e.emit_to_string(&src))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(&src))?;
    Ok((module, info))
}

#[cfg(test)]
mod tests {
    #[test]
    fn joined_shader_parses_and_validates() {
        if let Err(e) = super::validate() {
            panic!("WGSL does not validate:\n{e}");
        }
    }
}
