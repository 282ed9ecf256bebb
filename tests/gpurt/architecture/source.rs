//! Reading one source file for the module graph: comments and literals blanked out,
//! `#[cfg(test)]` modules dropped, and what is left read for the modules it declares, the
//! macros it exports, and every path it names (`a::b` in code, each leaf of a `use` tree).

/// A source file's text with comments and string and character literals blanked out
/// (a literal becomes `""` or a space), line breaks kept so that line numbers stay true.
pub(super) fn strip(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    // Skips `c[from..to]`, keeping its line breaks.
    let skip = |out: &mut String, from: usize, to: usize| {
        out.extend(c[from..to.min(c.len())].iter().filter(|&&ch| ch == '\n'));
    };
    let find = |from: usize, pat: &[char]| {
        (from..c.len())
            .find(|&k| c[k..].starts_with(pat))
            .unwrap_or(c.len())
    };
    let mut i = 0;
    while i < c.len() {
        let at = |k: usize| c.get(i + k).copied().unwrap_or('\0');
        let after_word = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
        // A raw string: `r` or `br`, hashes, a quote.
        let prefix = match (at(0), at(1)) {
            _ if after_word => 0,
            ('r', _) => 1,
            ('b', 'r') => 2,
            _ => 0,
        };
        let hashes = (0..).take_while(|&h| at(prefix + h) == '#').count();
        let raw = prefix > 0 && at(prefix + hashes) == '"';
        if at(0) == '/' && at(1) == '/' {
            i = find(i, &['\n']);
        } else if at(0) == '/' && at(1) == '*' {
            let start = i;
            let mut depth = 0;
            while i < c.len() {
                match (c[i], c.get(i + 1)) {
                    ('/', Some('*')) => (depth, i) = (depth + 1, i + 2),
                    ('*', Some('/')) => (depth, i) = (depth - 1, i + 2),
                    _ => i += 1,
                }
                if depth == 0 {
                    break;
                }
            }
            skip(&mut out, start, i);
        } else if raw {
            let close: Vec<char> = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            let end = find(i + prefix + hashes + 1, &close);
            skip(&mut out, i, end);
            out.push_str("\"\"");
            i = end + close.len();
        } else if at(0) == '"' {
            let mut k = i + 1;
            while k < c.len() && c[k] != '"' {
                k += if c[k] == '\\' { 2 } else { 1 };
            }
            skip(&mut out, i, k);
            out.push_str("\"\"");
            i = k + 1;
        } else if at(0) == '\'' && (at(1) == '\\' || (at(2) == '\'' && at(1) != '\'')) {
            // A character literal (a lifetime has no closing quote).
            let mut k = i + 1;
            while k < c.len() && c[k] != '\'' {
                k += if c[k] == '\\' { 2 } else { 1 };
            }
            out.push(' ');
            i = k + 1;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// A token of stripped source: a word (identifier or keyword), `::`, or one other
/// character; with its line.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Token {
    pub(super) text: String,
    pub(super) line: usize,
}

pub(super) fn tokens(stripped: &str) -> Vec<Token> {
    let mut out = Vec::new();
    for (n, line) in stripped.lines().enumerate() {
        let c: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < c.len() {
            let start = i;
            if c[i].is_alphanumeric() || c[i] == '_' {
                while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                    i += 1;
                }
            } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
                i += 2;
            } else if c[i].is_whitespace() {
                i += 1;
                continue;
            } else {
                i += 1;
            }
            out.push(Token {
                text: c[start..i].iter().collect(),
                line: n + 1,
            });
        }
    }
    out
}

/// The tokens without the `#[cfg(test)]` modules (inline or declared).
fn without_test_modules(toks: Vec<Token>) -> Vec<Token> {
    let text = |k: usize| toks.get(k).map_or("", |t| t.text.as_str());
    let mut out = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        let cfg_test = ["#", "[", "cfg", "(", "test", ")", "]"];
        if !(0..cfg_test.len()).all(|k| text(i + k) == cfg_test[k]) {
            out.push(toks[i].clone());
            i += 1;
            continue;
        }
        // Past other attributes and a visibility, is it a module?
        let mut j = i + cfg_test.len();
        loop {
            if text(j) == "#" && text(j + 1) == "[" {
                while j < toks.len() && text(j) != "]" {
                    j += 1;
                }
                j += 1;
            } else if text(j) == "pub" {
                j += 1;
                if text(j) == "(" {
                    while j < toks.len() && text(j) != ")" {
                        j += 1;
                    }
                    j += 1;
                }
            } else {
                break;
            }
        }
        if text(j) != "mod" {
            out.push(toks[i].clone());
            i += 1;
            continue;
        }
        j += 2;
        if text(j) == "{" {
            let mut depth = 0;
            while j < toks.len() {
                depth += match text(j) {
                    "{" => 1,
                    "}" => -1,
                    _ => 0,
                };
                j += 1;
                if depth == 0 {
                    break;
                }
            }
        }
        i = j + usize::from(text(j) == ";");
    }
    out
}

/// A path a file names: its segments (and the name `use ... as` gives it), its line, and
/// whether it is a `pub use`.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    pub segments: Vec<String>,
    pub alias: Option<String>,
    pub line: usize,
    pub public_use: bool,
}

/// What a file says about modules: the modules it declares (`mod x;`), the macros it
/// exports, and every path it names that may lead to a module.
#[derive(Default)]
pub struct Parsed {
    pub declares: Vec<String>,
    pub macros: Vec<String>,
    pub names: Vec<Named>,
}

fn is_word(t: &str) -> bool {
    t.chars().all(|c| c.is_alphanumeric() || c == '_') && !t.is_empty()
}

/// Parses the use tree at `toks[*i..]` after `prefix`, pushing one `Named` a leaf.
fn use_tree(toks: &[Token], i: &mut usize, prefix: &[String], public: bool, out: &mut Vec<Named>) {
    let text = |k: usize| toks.get(k).map_or("", |t| t.text.as_str());
    let mut segments = prefix.to_vec();
    loop {
        match text(*i) {
            "{" => {
                *i += 1;
                while *i < toks.len() && text(*i) != "}" {
                    use_tree(toks, i, &segments, public, out);
                    if text(*i) == "," {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            "::" => *i += 1,
            w if is_word(w) || w == "*" => {
                segments.push(w.to_string());
                let line = toks[*i].line;
                *i += 1;
                if text(*i) == "::" {
                    continue;
                }
                let alias = (text(*i) == "as").then(|| {
                    *i += 2;
                    text(*i - 1).to_string()
                });
                if segments.last().is_some_and(|s| s == "self" || s == "*") && segments.len() > 1 {
                    segments.pop();
                }
                out.push(Named {
                    segments,
                    alias,
                    line,
                    public_use: public,
                });
                return;
            }
            _ => {
                *i += 1;
                return;
            }
        }
    }
}

/// Reads a file's declarations and every path it names (`a::b`, and each leaf of a `use`
/// tree); which of them lead to a module is for `Graph::of` to say.
pub fn parse(src: &str) -> Parsed {
    let toks = without_test_modules(tokens(&strip(src)));
    let text = |k: usize| toks.get(k).map_or("", |t| t.text.as_str());
    let mut p = Parsed::default();
    let mut i = 0;
    while i < toks.len() {
        let t = text(i);
        if t == "mod" && is_word(text(i + 1)) && text(i + 2) == ";" {
            p.declares.push(text(i + 1).to_string());
            i += 3;
        } else if t == "macro_export" {
            while i < toks.len() && text(i) != "macro_rules" {
                i += 1;
            }
            p.macros.push(text(i + 2).to_string());
            i += 3;
        } else if t == "use" && (i == 0 || text(i - 1) != "::") {
            let public = text(i.saturating_sub(1)) == "pub"
                || (text(i.saturating_sub(1)) == ")" && {
                    let mut k = i - 1;
                    while k > 0 && text(k) != "(" {
                        k -= 1;
                    }
                    k > 0 && text(k - 1) == "pub"
                });
            i += 1;
            use_tree(&toks, &mut i, &[], public, &mut p.names);
        } else if is_word(t)
            && text(i + 1) == "::"
            && !matches!(text(i.wrapping_sub(1)), "::" | "$")
        {
            let line = toks[i].line;
            let mut segments = vec![t.to_string()];
            i += 1;
            while text(i) == "::" && is_word(text(i + 1)) {
                segments.push(text(i + 1).to_string());
                i += 2;
            }
            p.names.push(Named {
                segments,
                alias: None,
                line,
                public_use: false,
            });
        } else {
            i += 1;
        }
    }
    p
}
