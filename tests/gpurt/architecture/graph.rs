//! The module graph of a set of source files: each crate's module tree from its root's
//! `mod` declarations, every path a file names resolved to the module it reaches (through
//! `pub use` re-exports and exported macros), the arrows between modules placed in the
//! graph of the top-level modules and in that of each directory, and their circles.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use super::source::parse;

/// The library's name, as the binary writes it.
pub const LIB: &str = "gpurt";

/// A module: of the library or of the binary, and its path from that crate's root.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Module {
    pub bin: bool,
    pub path: Vec<String>,
}

impl Module {
    fn root(bin: bool) -> Module {
        Module { bin, path: vec![] }
    }

    fn child(&self, name: &str) -> Module {
        let mut path = self.path.clone();
        path.push(name.to_string());
        Module {
            bin: self.bin,
            path,
        }
    }

    /// Its top-level module: the binary's root is `main`, the library's root is none.
    pub fn top(&self) -> Option<String> {
        match (self.path.first(), self.bin) {
            (Some(first), _) => Some(first.clone()),
            (None, true) => Some("main".into()),
            (None, false) => None,
        }
    }
}

/// One use of a module by another, and where it is written.
#[derive(Clone, Debug)]
pub struct Arrow {
    pub from: Module,
    pub to: Module,
    pub file: String,
    pub line: usize,
}

/// The modules of a set of source files (paths relative to `src/`) and the arrows
/// between them.
pub struct Graph {
    pub files: BTreeMap<Module, String>,
    pub arrows: Vec<Arrow>,
    /// Files that are no module of either crate.
    pub orphans: Vec<String>,
}

/// The file of module `name`, declared in file `parent`.
fn child_file(files: &BTreeMap<String, String>, parent: &str, name: &str) -> Option<String> {
    let dir = if parent == "lib.rs" || parent == "main.rs" {
        String::new()
    } else if let Some(dir) = parent.strip_suffix("mod.rs") {
        dir.to_string()
    } else {
        format!("{}/", parent.trim_end_matches(".rs"))
    };
    [format!("{dir}{name}.rs"), format!("{dir}{name}/mod.rs")]
        .into_iter()
        .find(|f| files.contains_key(f))
}

impl Graph {
    pub fn of(sources: &[(&str, &str)]) -> Graph {
        let texts: BTreeMap<String, String> = sources
            .iter()
            .map(|(p, s)| (p.to_string(), s.to_string()))
            .collect();
        // The module tree, from each crate's root through its `mod` declarations.
        let mut files = BTreeMap::new();
        let mut parsed = BTreeMap::new();
        let mut queue: VecDeque<(Module, String)> = ["lib.rs", "main.rs"]
            .into_iter()
            .filter(|r| texts.contains_key(*r))
            .map(|r| (Module::root(r == "main.rs"), r.to_string()))
            .collect();
        while let Some((module, file)) = queue.pop_front() {
            let p = parse(&texts[&file]);
            for name in &p.declares {
                if let Some(f) = child_file(&texts, &file, name) {
                    queue.push_back((module.child(name), f));
                }
            }
            files.insert(module.clone(), file);
            parsed.insert(module, p);
        }
        let orphans = texts
            .keys()
            .filter(|f| !files.values().any(|g| g == *f))
            .cloned()
            .collect();
        let modules: BTreeSet<Module> = files.keys().cloned().collect();
        // Names a module re-exports (`pub use`, exported macros at the library's root).
        let mut reexports: BTreeMap<(Module, String), (Module, Vec<String>)> = BTreeMap::new();
        for (module, p) in &parsed {
            for n in p.names.iter().filter(|n| n.public_use) {
                let name = n.alias.clone().or_else(|| n.segments.last().cloned());
                reexports.insert(
                    (module.clone(), name.unwrap()),
                    (module.clone(), n.segments.clone()),
                );
            }
            for m in &p.macros {
                let at = (module.clone(), vec!["self".to_string()]);
                reexports.insert((Module::root(false), m.clone()), at);
            }
        }
        // The module a path named in `from` reaches, following re-exports.
        let resolve = |from: &Module, segments: &[String]| -> Option<Module> {
            let mut at = (from.clone(), segments.to_vec());
            for _ in 0..8 {
                let (from, segments) = at;
                let first = segments.first()?.as_str();
                let supers = segments.iter().take_while(|s| *s == "super").count();
                let (mut module, rest) = match first {
                    "crate" => (Module::root(from.bin), &segments[1..]),
                    LIB if from.bin => (Module::root(false), &segments[1..]),
                    "self" => (from.clone(), &segments[1..]),
                    "super" if supers <= from.path.len() => {
                        let path = from.path[..from.path.len() - supers].to_vec();
                        (
                            Module {
                                path,
                                ..from.clone()
                            },
                            &segments[supers..],
                        )
                    }
                    // Uniform paths: a child module's name starts a path too.
                    _ if modules.contains(&from.child(first)) => (from.clone(), &segments[..]),
                    _ => return None,
                };
                let mut through = None;
                for s in rest {
                    if modules.contains(&module.child(s)) {
                        module = module.child(s);
                    } else {
                        through = reexports.get(&(module.clone(), s.clone())).cloned();
                        break;
                    }
                }
                match through {
                    Some(next) => at = next,
                    None => return Some(module),
                }
            }
            None
        };
        let mut arrows = Vec::new();
        for (from, p) in &parsed {
            for n in &p.names {
                let Some(to) = resolve(from, &n.segments) else {
                    continue;
                };
                // A facade's `pub use` of its own descendants is no arrow.
                let own = to.bin == from.bin && to.path.starts_with(&from.path);
                if to == *from || (n.public_use && own) || (!to.bin && to.path.is_empty()) {
                    continue;
                }
                arrows.push(Arrow {
                    from: from.clone(),
                    to,
                    file: files[from].clone(),
                    line: n.line,
                });
            }
        }
        Graph {
            files,
            arrows,
            orphans,
        }
    }

    /// Each arrow placed in the graphs it belongs to: the top-level modules' (`""`), and
    /// that of the directory holding both ends (a directory's own `mod.rs` is `mod.rs`).
    pub fn placed(&self) -> BTreeMap<String, Vec<(String, String, &Arrow)>> {
        let mut graphs: BTreeMap<String, Vec<_>> = BTreeMap::new();
        for a in &self.arrows {
            if let (Some(f), Some(t)) = (a.from.top(), a.to.top())
                && f != t
            {
                graphs.entry(String::new()).or_default().push((f, t, a));
            }
            if a.from.bin != a.to.bin {
                continue;
            }
            let (f, t) = (&a.from.path, &a.to.path);
            let k = f.iter().zip(t).take_while(|(x, y)| x == y).count();
            let node = |p: &[String]| p.get(k).cloned().unwrap_or_else(|| "mod.rs".into());
            if k >= 1 {
                let dir = f[..k].join("/");
                graphs.entry(dir).or_default().push((node(f), node(t), a));
            }
        }
        graphs
    }
}

/// The shortest way from `from` to `to` along `next`, both ends included.
fn shortest<'a>(
    next: &BTreeMap<&'a str, BTreeMap<&'a str, &Arrow>>,
    from: &'a str,
    to: &'a str,
) -> Option<Vec<&'a str>> {
    let mut came: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = VecDeque::from([from]);
    while let Some(n) = queue.pop_front() {
        if n == to {
            let mut path = vec![to];
            while let Some(&p) = came.get(path.last().unwrap()) {
                path.push(p);
                if p == from {
                    break;
                }
            }
            path.reverse();
            return Some(path);
        }
        for &m in next.get(n).into_iter().flat_map(|m| m.keys()) {
            if m != from && !came.contains_key(m) {
                came.insert(m, n);
                queue.push_back(m);
            }
        }
    }
    None
}

/// The circles of one graph: for every arrow between two modules that reach each other,
/// that arrow and the shortest way back; each circle once, from its smallest module.
pub fn circles<'a>(edges: &[(String, String, &'a Arrow)]) -> Vec<Vec<(String, &'a Arrow)>> {
    let mut next: BTreeMap<&str, BTreeMap<&str, &Arrow>> = BTreeMap::new();
    for (f, t, a) in edges {
        next.entry(f.as_str())
            .or_default()
            .entry(t.as_str())
            .or_insert(*a);
    }
    let mut seen = BTreeSet::new();
    let mut out = Vec::new();
    for (f, t) in next
        .iter()
        .flat_map(|(f, ts)| ts.keys().map(move |t| (*f, *t)))
    {
        let Some(back) = shortest(&next, t, f) else {
            continue;
        };
        let mut ring: Vec<&str> = std::iter::once(f)
            .chain(back[..back.len() - 1].iter().copied())
            .collect();
        let start = (0..ring.len()).min_by_key(|&k| ring[k]).unwrap();
        ring.rotate_left(start);
        if seen.insert(ring.clone()) {
            let hops = (0..ring.len()).map(|k| (ring[k], ring[(k + 1) % ring.len()]));
            out.push(hops.map(|(a, b)| (a.to_string(), next[a][b])).collect());
        }
    }
    out
}
