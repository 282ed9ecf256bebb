//! The words an NFF file may use, and the one a misspelt word most probably meant: read by
//! the statement loop and by the `v` block alike.

/// The statements (entity keywords) of the format, ours included.
pub(super) const STATEMENTS: [&str; 28] = [
    "v", "b", "l", "dl", "al", "am", "f", "c", "s", "p", "pp", "pl", "aabb", "mesh",
    // BART's AFF.
    "a", "k", "x", "xs", "}", "la", "fm", "tt", "ttp", "tpp", "tpa", "m", "i", "d",
];

/// The keyword `word` is most probably a misspelling of, if any: of three letters or more,
/// and close to it (Jaro similarity 0.8 or more; shorter keywords are too alike to tell).
pub(super) fn closest<'k>(word: &[u8], keywords: &[&'k str]) -> Option<&'k str> {
    let word = std::str::from_utf8(word).ok().filter(|w| w.len() >= 3)?;
    keywords
        .iter()
        .filter(|k| k.len() >= 3)
        .map(|k| (strsim::jaro(word, k), *k))
        .filter(|(score, _)| *score >= 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, k)| k)
}

/// Words other tracers' scene files use where NFF has a statement, with that statement:
/// a file in another dialect is told NFF's word (compared ignoring case).
pub(super) const OTHER_WORDS: [(&str, &str); 15] = [
    ("sphere", "s"),
    ("cone", "c"),
    ("cylinder", "c"),
    ("polygon", "p"),
    ("triangle", "p"),
    ("face", "p"),
    ("light", "l"),
    ("camera", "v"),
    ("view", "v"),
    ("material", "f"),
    ("fill", "f"),
    ("background", "b"),
    ("plane", "pl"),
    ("box", "aabb"),
    ("include", "mesh"),
];

/// NFF's statement for `word`, another tracer's word for it (`OTHER_WORDS`), if any.
pub(super) fn nff_word_for(word: &[u8]) -> Option<&'static str> {
    OTHER_WORDS
        .iter()
        .find(|(other, _)| other.as_bytes().eq_ignore_ascii_case(word))
        .map(|&(_, nff)| nff)
}

/// The keywords of a `v` block.
pub(super) const VIEW_KEYWORDS: [&str; 8] = [
    "from",
    "at",
    "up",
    "angle",
    "hither",
    "resolution",
    "aperture",
    "focal",
];
