//! The module graph of `src/`, read from the source text, against the layout of
//! docs/architecture.md: no import circle between the modules of one directory nor between
//! top-level modules, and every arrow pointing down the layer table. An arrow is a use of
//! one module by another: `use crate::...` (and `super::`, `self::` and a child module's
//! name), a `crate::x::` path in code, and `gpurt::` in the binary (`src/main.rs`, `src/cli/`).
//! Comments, string literals and `#[cfg(test)]` modules do not count; a `pub use` of a
//! module's own child (a `mod.rs` facade) is no arrow, and paths through it reach the child.
//! The checker is tested on small synthetic crates; the test over the real `src/` waits for
//! the re-cut. `source` reads a file, `graph` joins the files into modules and arrows.

mod door;
mod graph;
mod source;

use std::collections::BTreeSet;
use std::path::Path;

use graph::{Arrow, Graph, Module, circles};

/// The layers of docs/architecture.md, top first. A module may use the modules of the
/// layers below its own, and those of its own layer as long as no circle forms.
const LAYERS: &[&[&str]] = &[
    &["main", "cli"],
    &["commands"],
    &["view"],
    &["session"],
    &["compare"],
    &["gpu"],
    &["cpu"],
    &["film", "counters"],
    &["frame"],
    &["pack"],
    &["bvh"],
    &["scene"],
    &["gpu_types"],
    &["util"],
];

/// What the check finds, one line each: circles (with the arrows that close them, by
/// file and line), arrows pointing up the layer table, top-level modules the table does
/// not name, and files that are no module.
#[derive(Debug, Default)]
struct Report {
    circles: Vec<String>,
    upward: Vec<String>,
    unlisted: Vec<String>,
    /// Files neither crate reaches through its `mod` declarations.
    strays: Vec<String>,
}

impl Report {
    fn is_clean(&self) -> bool {
        [&self.circles, &self.upward, &self.unlisted, &self.strays]
            .iter()
            .all(|l| l.is_empty())
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        for (title, lines) in [
            ("import circles", &self.circles),
            ("arrows pointing up the layer table", &self.upward),
            (
                "top-level modules the layer table does not name",
                &self.unlisted,
            ),
            ("files that are no module", &self.strays),
        ] {
            writeln!(f, "{title}: {}", lines.len())?;
            for l in lines {
                writeln!(f, "  {l}")?;
            }
        }
        Ok(())
    }
}

/// Checks the files `sources` (paths relative to `src/`, and their text) against the
/// layer table `layers`.
fn check(sources: &[(&str, &str)], layers: &[&[&str]]) -> Report {
    let graph = Graph::of(sources);
    let mut report = Report::default();
    let at = |a: &Arrow| format!("src/{}:{}", a.file, a.line);
    for (dir, edges) in graph.placed() {
        let place = if dir.is_empty() {
            "top level".to_string()
        } else {
            format!("src/{dir}/")
        };
        for ring in circles(&edges) {
            let names: Vec<&str> = ring.iter().map(|(n, _)| n.as_str()).collect();
            let arrows: Vec<String> = ring.iter().map(|(_, a)| at(a)).collect();
            report.circles.push(format!(
                "{place}: {} -> {} (arrows at {})",
                names.join(" -> "),
                names[0],
                arrows.join(", ")
            ));
        }
    }
    let layer = |name: &str| layers.iter().position(|l| l.contains(&name));
    let tops: BTreeSet<String> = graph.files.keys().filter_map(Module::top).collect();
    report.unlisted = tops
        .iter()
        .filter(|t| layer(t).is_none())
        .cloned()
        .collect();
    let mut upward = BTreeSet::new();
    for a in &graph.arrows {
        let (Some(f), Some(t)) = (a.from.top(), a.to.top()) else {
            continue;
        };
        if let (Some(lf), Some(lt)) = (layer(&f), layer(&t))
            && lf > lt
        {
            upward.insert((a.file.clone(), a.line, f, t));
        }
    }
    report.upward = upward
        .into_iter()
        .map(|(file, line, f, t)| format!("src/{file}:{line}: {f} -> {t}"))
        .collect();
    report.strays = graph.orphans.iter().map(|o| format!("src/{o}")).collect();
    report
}

/// Every `.rs` file under `dir`, as (path relative to it, text).
fn sources_under(dir: &Path) -> Vec<(String, String)> {
    crate::common::files_with(dir, &[".rs"])
        .into_iter()
        .map(|p| {
            let rel = p
                .strip_prefix(dir)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let text =
                std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (rel, text)
        })
        .collect()
}

#[test]
fn src_has_no_import_circle_and_no_arrow_up_the_layers() {
    let src = sources_under(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let sources: Vec<(&str, &str)> = src.iter().map(|(p, t)| (p.as_str(), t.as_str())).collect();
    let report = check(&sources, LAYERS);
    println!("{report}");
    assert!(report.is_clean(), "{report}");
}

// ---------------------------------------------------------------------------------------
// The checker itself, on small synthetic crates
// ---------------------------------------------------------------------------------------

/// Layers for the synthetic crates: `app` over `model` over `base`.
const TOY_LAYERS: &[&[&str]] = &[&["main", "cli", "app"], &["model", "store"], &["base"]];

#[test]
fn a_circle_in_one_directory_is_found_with_its_files_and_lines() {
    let report = check(
        &[
            ("lib.rs", "pub mod model;\n"),
            (
                "model/mod.rs",
                "//! A model.\npub mod a;\npub mod b;\npub mod c;\n",
            ),
            ("model/a.rs", "use super::b::B;\npub struct A;\n"),
            (
                "model/b.rs",
                "pub struct B;\n\nfn f() -> crate::model::c::C {\n    todo!()\n}\n",
            ),
            ("model/c.rs", "pub struct C(super::a::A);\n"),
        ],
        TOY_LAYERS,
    );
    assert_eq!(
        report.circles,
        [
            "src/model/: a -> b -> c -> a (arrows at src/model/a.rs:1, src/model/b.rs:3, src/model/c.rs:1)"
        ]
    );
    assert!(
        report.upward.is_empty() && report.unlisted.is_empty(),
        "{report}"
    );
}

#[test]
fn a_circle_between_top_level_modules_is_found() {
    let report = check(
        &[
            ("lib.rs", "pub mod model;\npub mod store;\n"),
            (
                "model.rs",
                "use crate::store::Store;\npub struct Model(Store);\n",
            ),
            (
                "store.rs",
                "pub struct Store;\nimpl Store {\n    fn m(&self) -> crate::model::Model { todo!() }\n}\n",
            ),
        ],
        TOY_LAYERS,
    );
    assert_eq!(
        report.circles,
        ["top level: model -> store -> model (arrows at src/model.rs:1, src/store.rs:3)"]
    );
    assert!(report.upward.is_empty(), "one layer: {report}");
}

#[test]
fn an_arrow_up_the_layers_an_unlisted_module_and_a_stray_file_are_found() {
    let report = check(
        &[
            (
                "lib.rs",
                "pub mod app;\npub mod base;\npub mod model;\npub mod extra;\n",
            ),
            ("app.rs", "use crate::model::Model;\n"),
            ("model.rs", "pub struct Model;\n"),
            (
                "base.rs",
                "//! At the bottom.\n\npub fn f() {\n    let _ = crate::app::run;\n}\n",
            ),
            ("extra.rs", ""),
            ("old.rs", "use crate::app::run;\n"),
        ],
        TOY_LAYERS,
    );
    assert_eq!(report.upward, ["src/base.rs:4: base -> app"]);
    assert_eq!(report.unlisted, ["extra"]);
    assert_eq!(report.strays, ["src/old.rs"]);
    assert!(report.circles.is_empty(), "{report}");
}

/// A layered crate with everything the reader must see through: comments, strings and
/// test modules that name upper modules, a facade `pub use`, an exported macro, `super::`,
/// a child module named without a prefix, and the binary's `gpurt::` paths. It passes;
/// the same upward path in code, added to it, fails.
#[test]
fn a_clean_graph_passes_and_one_upward_path_in_code_fails_it() {
    let base = r##"//! Leaves. `crate::app` in a doc comment is no arrow.
#[macro_export]
macro_rules! say { ($($t:tt)*) => { println!($($t)*) }; }
/* crate::app::run /* nested */ crate::app::run */
pub const S: &str = "crate::app::run";
pub const R: &str = r#"use crate::app; "quoted""#;
pub const C: char = '"';
pub fn f<'a>(s: &'a str) -> &'a str { s }
#[cfg(test)]
mod tests {
    use crate::app::run;
}
"##;
    let clean = [
        (
            "lib.rs",
            "pub mod app;\npub mod base;\npub mod model;\npub use base::S;\n",
        ),
        (
            "main.rs",
            "mod cli;\nuse gpurt::app;\nfn main() { cli::go(); gpurt::say!(\"x\"); }\n",
        ),
        (
            "cli/mod.rs",
            "use gpurt::model::Model;\npub fn go() { let _ = gpurt::S; }\n",
        ),
        (
            "app.rs",
            "use crate::model::{self, Thing};\npub fn run() { crate::say!(\"{}\", model::part::P); }\n",
        ),
        (
            "model/mod.rs",
            "pub mod part;\npub use part::Thing;\nfn g() { part::h(); }\n",
        ),
        (
            "model/part.rs",
            "use super::super::base::f;\npub struct Thing;\npub const P: u8 = 1;\npub fn h() {}\n",
        ),
        ("base.rs", base),
    ];
    let report = check(&clean, TOY_LAYERS);
    assert!(report.is_clean(), "{report}");
    let graph = Graph::of(&clean);
    let arrows: BTreeSet<String> = graph
        .arrows
        .iter()
        .map(|a| {
            format!(
                "{}:{} {:?} -> {:?}",
                a.file,
                a.line,
                a.from.top(),
                a.to.path
            )
        })
        .collect();
    for want in [
        "main.rs:2 Some(\"main\") -> [\"app\"]",
        "main.rs:3 Some(\"main\") -> [\"cli\"]",
        "main.rs:3 Some(\"main\") -> [\"base\"]",
        "cli/mod.rs:2 Some(\"cli\") -> [\"base\"]",
        "app.rs:1 Some(\"app\") -> [\"model\", \"part\"]",
        "app.rs:2 Some(\"app\") -> [\"base\"]",
        "model/mod.rs:3 Some(\"model\") -> [\"model\", \"part\"]",
        "model/part.rs:1 Some(\"model\") -> [\"base\"]",
    ] {
        assert!(arrows.contains(want), "{want} missing from {arrows:#?}");
    }
    assert!(
        !arrows.iter().any(|a| a.starts_with("base.rs")),
        "{arrows:#?}"
    );
    let upward = base.replace(
        "pub fn f<'a>",
        "pub fn g() { crate::app::run(); }\npub fn f<'a>",
    );
    let mut broken = clean;
    broken[6] = ("base.rs", &upward);
    let report = check(&broken, TOY_LAYERS);
    assert_eq!(report.upward, ["src/base.rs:8: base -> app"], "{report}");
}
