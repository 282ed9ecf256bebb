//! A glTF file's buffers, resolved: the `.glb` binary chunk, data URIs, and files beside
//! the model (never outside its folder); and the accessors checked against them before the
//! `gltf` crate reads them (its reader trusts counts, strides and types, and would panic or
//! overflow on a file that lies).

use std::path::Path;

use base64::Engine;
use gltf::accessor::{DataType, Dimensions};

use crate::scene::io;
use crate::util::error::{Error, Result};
use crate::util::limits::MAX_FILE_BYTES;

/// Every buffer's bytes, in the file's order.
pub fn resolve(
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    name: &str,
    dir: Option<&Path>,
) -> Result<Vec<Vec<u8>>> {
    let err = |msg: String| Error::Scene {
        file: name.to_string(),
        msg,
    };
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let what = format!("buffer {}", b.index());
        let bytes = match b.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| err(format!("{what} is the binary chunk, which the file lacks")))?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(data) => data_uri(data).map_err(|e| err(format!("{what}: {e}")))?,
                None => file(uri, dir, &what, &err)?,
            },
        };
        if (bytes.len() as u64) < b.length() as u64 {
            return Err(err(format!(
                "{what} declares {} bytes but holds {}",
                b.length(),
                bytes.len()
            )));
        }
        out.push(bytes);
    }
    Ok(out)
}

/// The bytes of a data URI, `data:` taken off.
pub fn data_uri(data: &str) -> std::result::Result<Vec<u8>, String> {
    let (_, payload) = data
        .split_once(";base64,")
        .ok_or("a data URI that is not base64")?;
    base64::engine::general_purpose::STANDARD
        .decode(payload)
        .map_err(|e| format!("bad base64 in its data URI ({e})"))
}

/// A buffer in a file named by a relative URI: inside the model's folder only.
fn file(
    uri: &str,
    dir: Option<&Path>,
    what: &str,
    err: &dyn Fn(String) -> Error,
) -> Result<Vec<u8>> {
    let rel = percent_decode(uri);
    let Some(dir) = dir else {
        return Err(err(format!(
            "{what} is in the file '{rel}', which must be given with the model (or the model made self-contained: .glb, or data URIs)"
        )));
    };
    io::read_inside(dir, &rel, MAX_FILE_BYTES).map_err(|e| err(format!("{what}: {e}")))
}

/// `%20` and the like in a URI made bytes again (a malformed escape is kept as written).
pub fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (
            b[i],
            b.get(i + 1).copied().and_then(hex),
            b.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, ..) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Checks that accessor `a` holds `dims` of one of `types`, is not sparse, and that every
/// element it names lies inside its view and the view inside its buffer, so that reading
/// it cannot fail. `what` names it in messages.
pub fn check(
    a: &gltf::Accessor,
    dims: Dimensions,
    types: &[DataType],
    buffers: &[Vec<u8>],
    what: &str,
    err: &dyn Fn(String) -> Error,
) -> Result<()> {
    let idx = a.index();
    if a.sparse().is_some() {
        return Err(err(format!(
            "accessor {idx} ({what}) is sparse, which gpurt does not read"
        )));
    }
    if a.dimensions() != dims || !types.contains(&a.data_type()) {
        return Err(err(format!(
            "accessor {idx} ({what}) holds {:?} of {:?}, not {dims:?} of {types:?}",
            a.dimensions(),
            a.data_type()
        )));
    }
    let Some(view) = a.view() else {
        return Err(err(format!("accessor {idx} ({what}) has no buffer view")));
    };
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    let buffer = &buffers[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length());
    let last = (a.count().max(1) - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(a.offset()))
        .and_then(|x| x.checked_add(size));
    let fits = stride >= size
        && view_end.is_some_and(|end| end <= buffer.len())
        && last.is_some_and(|end| end <= view.length());
    if !fits {
        return Err(err(format!(
            "accessor {idx} ({what}) reaches past its buffer view, or its view past buffer {}",
            view.buffer().index()
        )));
    }
    Ok(())
}
