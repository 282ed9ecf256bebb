//! A PLY file's header: its format, and its elements with their counts and properties,
//! read with the text readers' tokenizer (so that its errors point at a line and column).

use crate::scene::lex::{Lexer, Token};
use crate::util::error::Result;

/// How the body is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Ascii,
    /// Binary, big-endian when true.
    Binary(bool),
}

/// A property's number type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// Both spellings PLY writers use: the original (`uchar`) and the sized (`uint8`).
    fn named(name: &[u8]) -> Option<Scalar> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes in a binary body.
    pub fn size(self) -> u64 {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value a colour channel of this type has at full intensity: 255 for `uchar`,
    /// 65535 for `ushort`, 1 for floats (as writers use them).
    pub fn full(self) -> f64 {
        match self {
            Scalar::U8 | Scalar::I8 => 255.0,
            Scalar::U16 | Scalar::I16 => 65535.0,
            _ => 1.0,
        }
    }
}

/// A property: one number, or a list of numbers after its length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
pub struct Property {
    pub name: String,
    pub kind: Kind,
}

#[derive(Clone, Debug)]
pub struct Element {
    pub name: String,
    pub count: u64,
    pub props: Vec<Property>,
    /// Where its `element` line declares it.
    pub at: Token,
}

impl Element {
    /// The least bytes one of these takes in the body: in binary, its numbers with every
    /// list empty; in ASCII, a digit and a space a number.
    pub fn least_bytes(&self, format: Format) -> u64 {
        self.props
            .iter()
            .map(|p| match (format, p.kind) {
                (Format::Ascii, _) => 2,
                (_, Kind::Scalar(s)) => s.size(),
                (_, Kind::List { count, .. }) => count.size(),
            })
            .sum()
    }

    /// The index of the scalar property with one of `names`.
    pub fn scalar(&self, names: &[&str]) -> Option<(usize, Scalar)> {
        self.props
            .iter()
            .enumerate()
            .find_map(|(i, p)| match p.kind {
                Kind::Scalar(s) if names.contains(&p.name.as_str()) => Some((i, s)),
                _ => None,
            })
    }
}

pub struct Header {
    pub format: Format,
    pub elements: Vec<Element>,
}

/// Reads the header, up to and including `end_header`.
pub fn read(lx: &mut Lexer) -> Result<Header> {
    let first = lx.expect_token("'ply'")?;
    if lx.text(&first) != b"ply" {
        let msg = format!(
            "expected 'ply' (a PLY file's first line), found {}",
            lx.show(&first)
        );
        return Err(lx.error_at(&first, msg));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let t = lx.expect_token("'end_header'")?;
        match lx.text(&t) {
            b"format" => {
                let f = lx.expect_token("a format")?;
                format = Some(match lx.text(&f) {
                    b"ascii" => Format::Ascii,
                    b"binary_little_endian" => Format::Binary(false),
                    b"binary_big_endian" => Format::Binary(true),
                    _ => {
                        let msg = format!(
                            "expected ascii, binary_little_endian or binary_big_endian, found {}",
                            lx.show(&f)
                        );
                        return Err(lx.error_at(&f, msg));
                    }
                });
                let v = lx.expect_token("a version")?;
                if lx.text(&v) != b"1.0" {
                    let msg = format!("PLY version {} is not read (1.0 is)", lx.show(&v));
                    return Err(lx.error_at(&v, msg));
                }
            }
            b"comment" | b"obj_info" => lx.skip_line(t.line)?,
            b"element" => {
                let name = word(lx, "an element name")?;
                let (count, _) = lx.count(&format_args!("the number of '{name}' elements"))?;
                elements.push(Element {
                    name,
                    count: count.into(),
                    props: Vec::new(),
                    at: t,
                });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(lx.error_at(&t, "a property before any element"));
                };
                let kind = match scalar(lx)? {
                    None => Kind::List {
                        count: scalar(lx)?.filter(|s| s.is_integer()).ok_or_else(|| {
                            lx.error_here("a list's length must be an integer type")
                        })?,
                        item: scalar(lx)?.ok_or_else(|| lx.error_here("a list of lists"))?,
                    },
                    Some(s) => Kind::Scalar(s),
                };
                let name = word(lx, "a property name")?;
                element.props.push(Property { name, kind });
            }
            b"end_header" => break,
            _ => {
                let msg = format!(
                    "expected format, element, property, comment or end_header, found {}",
                    lx.show(&t)
                );
                return Err(lx.error_at(&t, msg));
            }
        }
    }
    let format = format.ok_or_else(|| lx.error_here("no 'format' line before 'end_header'"))?;
    Ok(Header { format, elements })
}

fn word(lx: &mut Lexer, what: &str) -> Result<String> {
    let t = lx.expect_token(what)?;
    Ok(String::from_utf8_lossy(lx.text(&t)).into_owned())
}

/// A type name: `Some` scalar, `None` for `list`.
fn scalar(lx: &mut Lexer) -> Result<Option<Scalar>> {
    let t = lx.expect_token("a property type")?;
    if lx.text(&t) == b"list" {
        return Ok(None);
    }
    match Scalar::named(lx.text(&t)) {
        Some(s) => Ok(Some(s)),
        None => {
            let msg = format!(
                "expected a type (char, uchar, short, ushort, int, uint, float, double, or int8 to float64) or 'list', found {}",
                lx.show(&t)
            );
            Err(lx.error_at(&t, msg))
        }
    }
}
