//! The words an NFF file may use, and the one a misspelt word most probably meant: read by
//! the statement loop and by the `v` block alike.

/// The statements (entity keywords) of the format, ours included.
pub(super) const STATEMENTS: [&str; 14] = [
    "v", "b", "l", "dl", "al", "am", "f", "c", "s", "p", "pp", "pl", "aabb", "mesh",
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
