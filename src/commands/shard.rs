//! One image rendered by several processes (`gpurt SCENE --shard I/N -o DIR/`): shard `I`
//! traces a band of rows and writes their linear sums and a manifest into DIR; `gpurt
//! merge DIR -o out.png` checks that every shard is there and belongs to the same scene
//! and settings, and assembles the image. A pixel's value does not depend on which other
//! pixels one process traces, so the merged image is the single-process one, to the byte.
//!
//! Files of shard `I` of `N`: `shard-I-of-N.rgbf32` (the band's per-pixel sums of the
//! samples, RGB, little-endian f32, row by row) and `shard-I-of-N.json` (the manifest),
//! each written atomically, the manifest last: a shard without its manifest does not
//! exist, and a retried shard never leaves a torn file.
//!
//! `Shard` (`I/N`, parsed here) is also what a batch run as a job array takes its share
//! of scenes by (`batch`).

use std::io::{Read, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::film::{Accumulator, Film};
use crate::frame::Shading;
use crate::util::atomic;
use crate::util::error::{Error, Result};

/// This process's share, `I/N`: of a batch run as a job array, scenes `index`,
/// `index + count`, `index + 2 count`, ... of the list every task is given (`take`); of
/// one image, the `index`-th band of rows or run of samples (`rows`, `samples`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Parses `I/N`, or `/N` with `I` from `SLURM_ARRAY_TASK_ID` (a Slurm job array) or
    /// `JOB_COMPLETION_INDEX` (a Kubernetes Indexed Job).
    pub fn parse(s: &str) -> std::result::Result<Shard, String> {
        Self::parse_with(s, |k| std::env::var(k).ok())
    }

    fn parse_with(
        s: &str,
        env: impl Fn(&str) -> Option<String>,
    ) -> std::result::Result<Shard, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("'{s}': expected I/N (or /N inside a job array)"))?;
        let count: u32 = match n.trim().parse() {
            Ok(n) if n >= 1 => n,
            _ => return Err(format!("'{s}': N must be a whole number, 1 or more")),
        };
        let (index, from) = if i.trim().is_empty() {
            let var = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"]
                .into_iter()
                .find_map(|k| env(k).map(|v| (v, k)));
            let (v, k) = var.ok_or_else(|| {
                format!(
                    "'{s}' takes its index from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX, \
                     and neither is set"
                )
            })?;
            let from = format!("{k}={}", v.trim());
            (v, from)
        } else {
            (i.to_string(), format!("'{s}'"))
        };
        match index.trim().parse::<u32>() {
            Ok(index) if index < count => Ok(Shard { index, count }),
            _ => Err(format!(
                "{from}: the shard index must be 0 to {} (with N = {count}; a Slurm array \
                 for N shards is --array=0-{})",
                count - 1,
                count - 1
            )),
        }
    }

    /// This shard's items.
    pub fn take<'a, T>(&self, items: &'a [T]) -> Vec<&'a T> {
        items
            .iter()
            .skip(self.index as usize)
            .step_by(self.count as usize)
            .collect()
    }
}

const FORMAT: &str = "gpurt-shard/1";

/// Shard I's part of `0..total`: the I-th of N runs as equal as whole units allow.
fn share(shard: Shard, total: u32) -> Range<u32> {
    let at = |i: u32| (u64::from(i) * u64::from(total) / u64::from(shard.count)) as u32;
    at(shard.index)..at(shard.index + 1)
}

/// The rows shard `shard` traces of an image `height` rows high (`--shard-by tiles`).
pub fn rows(shard: Shard, height: u32) -> Range<u32> {
    share(shard, height)
}

/// The samples shard `shard` traces of `spp` per pixel (`--shard-by samples`).
pub fn samples(shard: Shard, spp: u32) -> Range<u32> {
    share(shard, spp)
}

/// How an image is split between shards.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum By {
    /// Each shard traces every sample of a band of rows and stores the band's sums.
    Tiles,
    /// Each shard traces a run of samples of every pixel and stores each sample's image
    /// apart (`spp / N` images a shard), so that the merge adds them in sample order as
    /// a single process does, to the bit.
    Samples,
}

impl By {
    fn name(self) -> &'static str {
        match self {
            By::Tiles => "tiles",
            By::Samples => "samples",
        }
    }
}

/// What identifies a render: a 64-bit FNV-1a hash of the scene file, the view file, and
/// the settings text. Not cryptographic: it tells apart shards of different renders.
pub fn digest(scene: &Path, view: Option<&Path>, settings: &str) -> Result<String> {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    // A file through a buffer of its own size at most, never whole: a scene may be
    // gigabytes.
    let mut eat_file = |path: &Path| -> Result<()> {
        let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let mut buf = [0u8; 1 << 16];
        loop {
            match file.read(&mut buf) {
                Ok(0) => return Ok(()),
                Ok(n) => eat(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::io(path, e)),
            }
        }
    };
    eat_file(scene)?;
    if let Some(v) = view {
        eat_file(v)?;
    }
    eat(settings.as_bytes());
    Ok(format!("{h:016x}"))
}

/// A shard's description, as its manifest stores it.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    pub shard: Shard,
    pub by: By,
    /// `digest` of the scene, view and settings.
    pub digest: String,
    /// The settings, readable (size, samples, depth, ambient, seed, output, backend).
    pub settings: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub aov: u32,
    /// The highlight's model; a manifest without `shading` is Phong's.
    pub shading: Shading,
    /// The rows and samples this shard traced.
    pub rows: Range<u32>,
    pub samples: Range<u32>,
}

fn base(dir: &Path, shard: Shard) -> PathBuf {
    dir.join(format!("shard-{}-of-{}", shard.index, shard.count))
}

/// Writes a `--shard-by tiles` shard: rows `m.rows` of `accum`, which holds all `m.spp`
/// samples of them, into `dir`: the data, then the manifest.
pub fn write_tiles(dir: &Path, m: &Manifest, accum: &Accumulator) -> Result<()> {
    let w = m.width as usize;
    let band = &accum.sums.pixels[m.rows.start as usize * w..m.rows.end as usize * w];
    write(dir, m, band.iter().flatten())
}

/// Writes a `--shard-by samples` shard: `per_sample[k]` is the image of sample
/// `m.samples.start + k` alone.
pub fn write_samples(dir: &Path, m: &Manifest, per_sample: &[Film]) -> Result<()> {
    write(
        dir,
        m,
        per_sample.iter().flat_map(|f| f.pixels.iter().flatten()),
    )
}

fn write<'a>(dir: &Path, m: &Manifest, floats: impl Iterator<Item = &'a f32>) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let base = base(dir, m.shard);
    // Streamed: a samples shard holds a frame a sample (3 GiB a sample at 16384x16384),
    // which a copy as bytes would hold a second time.
    let data = base.with_extension("rgbf32");
    atomic::write_atomic_with(&data, |w| {
        for c in floats {
            w.write_all(&c.to_le_bytes())
                .map_err(|e| Error::io(&data, e))?;
        }
        Ok(())
    })?;
    let mut manifest = json!({
        "format": FORMAT,
        "shard": m.shard.index,
        "of": m.shard.count,
        "by": m.by.name(),
        "digest": m.digest,
        "settings": m.settings,
        "scene": m.scene,
        "width": m.width,
        "height": m.height,
        "spp": m.spp,
        "samples": [m.samples.start, m.samples.end],
        "aov": m.aov,
        "rows": [m.rows.start, m.rows.end],
        "data": base.with_extension("rgbf32").file_name().map(|n| n.to_string_lossy().into_owned()),
    });
    // Phong, the default, is left out: a Phong shard's manifest is then what a gpurt
    // without other models wrote, and shards of either merge.
    if m.shading != Shading::Phong {
        manifest["shading"] = json!(m.shading.name());
    }
    let text = serde_json::to_string_pretty(&manifest).expect("JSON of plain values");
    atomic::write_atomic(&base.with_extension("json"), text.as_bytes())
}

/// The most a shard manifest is read of: `write` writes under a kilobyte and the scene's
/// path (at most a few kilobytes).
const MAX_MANIFEST_BYTES: u64 = 1 << 20;

fn read_manifest(path: &Path) -> Result<Manifest> {
    let bad = |why: &str| Error::Scene {
        file: path.display().to_string(),
        msg: format!("not a gpurt shard manifest: {why}"),
    };
    // Read up to a bound: whatever a shard directory holds, no unbounded allocation.
    let bytes = crate::util::bounded::read(path, MAX_MANIFEST_BYTES)
        .map_err(|e| Error::io(path, e))?
        .ok_or_else(|| bad(&format!("longer than {MAX_MANIFEST_BYTES} bytes")))?;
    let text = std::io::read_to_string(bytes.as_slice()).map_err(|e| Error::io(path, e))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| bad(&e.to_string()))?;
    if v["format"] != FORMAT {
        return Err(bad(&format!("format is not {FORMAT}")));
    }
    let num = |k: &str| -> Result<u32> {
        v[k].as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .ok_or_else(|| bad(&format!("no '{k}'")))
    };
    let pair = |k: &str| -> Result<Range<u32>> {
        let a = v[k]
            .as_array()
            .filter(|a| a.len() == 2)
            .ok_or_else(|| bad(k))?;
        let n = |i: usize| a[i].as_u64().and_then(|n| u32::try_from(n).ok());
        match (n(0), n(1)) {
            (Some(lo), Some(hi)) if lo <= hi => Ok(lo..hi),
            _ => Err(bad(k)),
        }
    };
    let text_of = |k: &str| v[k].as_str().map(str::to_owned).ok_or_else(|| bad(k));
    let shard = Shard {
        index: num("shard")?,
        count: num("of")?,
    };
    let by = match v["by"].as_str() {
        Some("tiles") => By::Tiles,
        Some("samples") => By::Samples,
        _ => return Err(bad("'by' is neither tiles nor samples")),
    };
    let shading = match &v["shading"] {
        Value::Null => Shading::Phong,
        name => name
            .as_str()
            .and_then(Shading::from_name)
            .ok_or_else(|| bad(&format!("unknown 'shading' {name}")))?,
    };
    Ok(Manifest {
        shard,
        by,
        digest: text_of("digest")?,
        settings: text_of("settings")?,
        scene: text_of("scene")?,
        width: num("width")?,
        height: num("height")?,
        spp: num("spp")?,
        aov: num("aov")?,
        shading,
        rows: pair("rows")?,
        samples: pair("samples")?,
    })
}

/// Reads every shard in `dir`, checks that they are one render's N shards, and
/// assembles its accumulator (all samples of every pixel) and AOV.
pub fn merge(dir: &Path) -> Result<(Accumulator, u32)> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut manifests: Vec<(PathBuf, Manifest)> = Vec::new();
    for e in entries {
        let path = e.map_err(|e| Error::io(dir, e))?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if name.is_some_and(|n| n.starts_with("shard-") && n.ends_with(".json")) {
            let m = read_manifest(&path)?;
            manifests.push((path, m));
        }
    }
    manifests.sort_by_key(|(p, _)| p.clone());
    let Some((first_path, first)) = manifests.first().cloned() else {
        return Err(Error::Render(format!(
            "{}: no shards (shard-I-of-N.json) to merge",
            dir.display()
        )));
    };
    let n = first.shard.count;
    let mut have = vec![None; n as usize];
    for (path, m) in &manifests {
        let same = m.digest == first.digest
            && m.settings == first.settings
            && m.by == first.by
            && m.shard.count == n
            && (m.width, m.height, m.spp, m.aov, m.shading)
                == (
                    first.width,
                    first.height,
                    first.spp,
                    first.aov,
                    first.shading,
                );
        if !same {
            return Err(Error::Render(format!(
                "{} belongs to another render than {} (scene, view or settings differ: {} against {}); \
                 remove it or merge it apart",
                path.display(),
                first_path.display(),
                m.settings,
                first.settings
            )));
        }
        let (want_rows, want_samples) = match m.by {
            By::Tiles => (rows(m.shard, m.height), 0..m.spp),
            By::Samples => (0..m.height, samples(m.shard, m.spp)),
        };
        if (&m.rows, &m.samples) != (&want_rows, &want_samples) {
            return Err(Error::Render(format!(
                "{}: rows {:?} and samples {:?} are not shard {} of {}'s",
                path.display(),
                m.rows,
                m.samples,
                m.shard.index,
                n
            )));
        }
        have[m.shard.index as usize] = Some(m.clone());
    }
    if let Some(missing) = have.iter().position(Option::is_none) {
        return Err(Error::Render(format!(
            "{}: shard {missing} of {n} is missing (shard-{missing}-of-{n}.json); run it, then merge again",
            dir.display()
        )));
    }
    let mut accum = Accumulator::new(first.width, first.height);
    let w = first.width as usize;
    // In shard order, which is row order (tiles) or sample order (samples).
    for m in have.into_iter().flatten() {
        let data = base(dir, m.shard).with_extension("rgbf32");
        let file = std::fs::File::open(&data).map_err(|e| Error::io(&data, e))?;
        let len = file.metadata().map_err(|e| Error::io(&data, e))?.len();
        let images = match m.by {
            By::Tiles => 1,
            By::Samples => m.samples.len(),
        };
        let want = (images * m.rows.len() * w * 12) as u64;
        if len != want {
            return Err(Error::Render(format!(
                "{}: {len} bytes, expected {want} for rows {:?} and samples {:?}",
                data.display(),
                m.rows,
                m.samples
            )));
        }
        // Streamed a pixel at a time through a buffer, never read whole: a shard of
        // samples holds a whole frame for each of its samples.
        let mut reader = std::io::BufReader::with_capacity(1 << 20, file);
        let mut failed = None;
        let values = std::iter::from_fn(|| {
            let mut p = [0u8; 12];
            match reader.read_exact(&mut p) {
                Ok(()) => Some(
                    [0, 4, 8].map(|o| f32::from_le_bytes([p[o], p[o + 1], p[o + 2], p[o + 3]])),
                ),
                Err(e) => {
                    failed = Some(e);
                    None
                }
            }
        });
        let band = m.rows.start as usize * w..m.rows.end as usize * w;
        match m.by {
            By::Tiles => {
                for (px, v) in accum.sums.pixels[band].iter_mut().zip(values) {
                    *px = v;
                }
            }
            // One image per sample: added pixel by pixel in sample order, as one process
            // adds each sample to its running sum.
            By::Samples => {
                let pixels = band.len();
                let mut values = values;
                for _ in m.samples.clone() {
                    for (px, v) in accum
                        .sums
                        .pixels
                        .iter_mut()
                        .zip(values.by_ref().take(pixels))
                    {
                        for c in 0..3 {
                            px[c] += v[c];
                        }
                    }
                }
            }
        }
        // The file checked its length first, so only a file cut short since, or a failing
        // disk, ends the pixels early.
        if let Some(e) = failed {
            return Err(Error::io(&data, e));
        }
    }
    accum.samples = first.spp;
    Ok((accum, first.aov))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_a_batch_and_take_their_index_from_the_job_array() {
        let none = |_: &str| None;
        let s = Shard::parse_with("1/3", none).unwrap();
        assert_eq!(s.take(&[0, 1, 2, 3, 4, 5, 6]), [&1, &4]);
        // Every item lands in exactly one shard.
        let mut all: Vec<i32> = (0..3)
            .flat_map(|i| Shard { index: i, count: 3 }.take(&[0, 1, 2, 3, 4, 5, 6]))
            .copied()
            .collect();
        all.sort();
        assert_eq!(all, [0, 1, 2, 3, 4, 5, 6]);
        let slurm = |k: &str| (k == "SLURM_ARRAY_TASK_ID").then(|| "2".to_string());
        assert_eq!(
            Shard::parse_with("/4", slurm).unwrap(),
            Shard { index: 2, count: 4 }
        );
        let k8s = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(
            Shard::parse_with("/2", k8s).unwrap(),
            Shard { index: 0, count: 2 }
        );
        for (bad, want) in [
            ("3/3", "the shard index must be 0 to 2"),
            ("x/3", "the shard index must be 0 to 2"),
            ("1/0", "N must be a whole number"),
            ("2", "expected I/N"),
            ("/3", "neither is set"),
        ] {
            let e = Shard::parse_with(bad, none).unwrap_err();
            assert!(e.contains(want), "{bad}: {e}");
        }
        let e = Shard::parse_with("/2", |_| Some("5".into())).unwrap_err();
        assert!(e.contains("SLURM_ARRAY_TASK_ID=5"), "{e}");
    }

    #[test]
    fn the_bands_of_n_shards_cover_every_row_once() {
        for (h, n) in [(7, 3), (480, 7), (5, 5), (3, 8)] {
            let mut next = 0;
            for i in 0..n {
                let r = rows(Shard { index: i, count: n }, h);
                assert_eq!(r.start, next);
                next = r.end;
            }
            assert_eq!(next, h);
        }
    }

    /// A manifest past the bound is refused by name, without being read whole; one within
    /// it that is not a manifest is refused for what it lacks.
    #[test]
    fn a_manifest_too_long_is_refused_by_name() {
        let dir = crate::film::tests::scratch_dir("long-manifest");
        let path = dir.join("shard-0-of-1.json");
        let mut text = String::from("{\"format\": \"");
        text.push_str(&"x".repeat(MAX_MANIFEST_BYTES as usize));
        text.push_str("\"}");
        std::fs::write(&path, &text).unwrap();
        let err = merge(&dir).unwrap_err().to_string();
        assert!(err.contains("shard-0-of-1.json"), "{err}");
        assert!(
            err.contains(&format!("longer than {MAX_MANIFEST_BYTES} bytes")),
            "{err}"
        );
        std::fs::write(&path, "{\"format\": \"other\"}").unwrap();
        let err = merge(&dir).unwrap_err().to_string();
        assert!(
            err.contains("not a gpurt shard manifest: format is not"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
