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

    /// Writes SPIR-V (what wgpu hands Vulkan drivers) of both entry points with the
    /// override constants of every primitive kind on and off: naga's SPIR-V writer has
    /// rejected valid WGSL before.
    #[test]
    fn every_specialisation_translates_to_spirv() {
        let (module, info) = super::validate().expect("shader validates");
        let names: Vec<String> = module
            .overrides
            .iter()
            .filter_map(|(_, o)| o.name.clone())
            .collect();
        for (entry, on) in [
            ("main", 0.0),
            ("main", 1.0),
            ("resume", 0.0),
            ("resume", 1.0),
        ] {
            let constants = names
                .iter()
                .map(|n| {
                    let value = match n.as_str() {
                        "AOV" => 0.0,
                        "STACK" => crate::gpu_types::TRAVERSAL_STACK as f64,
                        _ => on,
                    };
                    (n.clone(), value)
                })
                .collect();
            let (module, info) = naga::back::pipeline_constants::process_overrides(
                &module,
                &info,
                Some((naga::ShaderStage::Compute, entry)),
                &constants,
            )
            .expect("overrides apply");
            naga::back::spv::write_vec(&module, &info, &Default::default(), None)
                .unwrap_or_else(|e| panic!("SPIR-V of {entry} for overrides = {on}: {e}"));
        }
    }
}
