//! Eric Haines' Standard Procedural Databases `mount` and `balls` at any size, written as
//! NFF the way the SPD generators write it (their `-r 1` output):
//!
//!     cargo run --release --example spd -- mount|balls SIZE > out.nff
//!
//! `mount` is a fractal mountain of 2 * 4^SIZE triangles (Carpenter's midpoint
//! subdivision) with a pyramid of four glass spheres; `balls` is the sphereflake, the sum
//! over n = 0..=SIZE of 9^n spheres, on a square floor.
//!
//! The formulas, constants and order of operations are those of the SPD's `mount.c`,
//! `balls.c` and `libvec.c`, in f64 as there, so the text matches theirs: numbers as C's
//! `%g` (six significant digits, trailing zeros dropped). `mount` keeps the old hash of
//! the original database; for SIZE > 7 its `A << (7 - SIZE)` term shifts by a negative
//! count, which x86-64 masks to six bits (`wrapping_shl` here): that is how the shared
//! mount-8 and mount-9 files were made.
//!
//! The scene streams out as it is generated: memory stays small at any size (an 8.4
//! million triangle mount-11 is about 1 GB of text).

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::io::{self, Write};

/// The two databases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    Mount,
    Balls,
}

impl Model {
    pub fn parse(name: &str) -> Option<Model> {
        match name {
            "mount" => Some(Model::Mount),
            "balls" => Some(Model::Balls),
            _ => None,
        }
    }

    /// The sizes accepted: beyond them the files would be absurdly large.
    pub fn sizes(self) -> std::ops::RangeInclusive<u32> {
        match self {
            Model::Mount => 1..=15,
            Model::Balls => 1..=10,
        }
    }
}

/// Writes `model` at `size` as NFF to `out`.
pub fn write_nff(model: Model, size: u32, out: impl Write) -> io::Result<()> {
    assert!(model.sizes().contains(&size), "size {size} out of range");
    let mut nff = Nff::new(out);
    match model {
        Model::Mount => mount(&mut nff, size)?,
        Model::Balls => balls(&mut nff, size)?,
    }
    nff.out.flush()
}

type Vec3 = [f64; 3];
type Vec4 = [f64; 4];
type Matrix = [[f64; 4]; 4];

// ---------------------------------------------------------------------------------------
// NFF output, as the SPD library prints it.

/// Formats lines into a reused buffer and writes them out.
struct Nff<W: Write> {
    out: W,
    line: String,
    tmp: String,
}

impl<W: Write> Nff<W> {
    fn new(out: W) -> Self {
        Nff {
            out,
            line: String::with_capacity(128),
            tmp: String::with_capacity(64),
        }
    }

    /// A line: `head` then each number as `%g`, space separated.
    fn line(&mut self, head: &str, nums: &[f64]) -> io::Result<()> {
        self.line.clear();
        self.line.push_str(head);
        for (i, &v) in nums.iter().enumerate() {
            if i > 0 || !head.is_empty() {
                self.line.push(' ');
            }
            push_g(&mut self.line, &mut self.tmp, v);
        }
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    fn background(&mut self, c: Vec3) -> io::Result<()> {
        self.line("b", &c)
    }

    /// The SPD viewpoint (aspect ratio is not part of NFF).
    fn viewpoint(
        &mut self,
        from: Vec3,
        at: Vec3,
        up: Vec3,
        angle: f64,
        hither: f64,
        res: (u32, u32),
    ) -> io::Result<()> {
        self.out.write_all(b"v\n")?;
        self.line("from", &from)?;
        self.line("at", &at)?;
        self.line("up", &up)?;
        self.line("angle", &[angle])?;
        self.line("hither", &[hither])?;
        writeln!(self.out, "resolution {} {}", res.0, res.1)
    }

    fn light(&mut self, p: Vec3) -> io::Result<()> {
        self.line("l", &p)
    }

    /// `lib_output_color`: the highlight half-angle `ang` (degrees) becomes a Phong power;
    /// ambient and the specular highlight share are not part of NFF.
    #[allow(clippy::too_many_arguments)]
    fn color(
        &mut self,
        c: Vec3,
        _ka: f64,
        kd: f64,
        ks: f64,
        _ks_spec: f64,
        ang: f64,
        kt: f64,
        ior: f64,
    ) -> io::Result<()> {
        let rad = PI * ang / 180.0;
        let phong = if rad <= 0.0 {
            100000.0
        } else if rad >= PI / 2.0 {
            1.0
        } else {
            0.5f64.ln() / rad.cos().ln()
        };
        self.line("f", &[c[0], c[1], c[2], kd, ks, phong, kt, ior])
    }

    fn sphere(&mut self, s: Vec4) -> io::Result<()> {
        self.line("s", &s)
    }

    /// `lib_output_polygon`: adjacent vertices closer than 1e-6 collapse into one (as
    /// balls' closed floor loop does), and what is left needs three vertices.
    fn polygon(&mut self, verts: &[Vec3]) -> io::Result<()> {
        let mut v = [[0.0; 3]; 8];
        let mut n = verts.len();
        v[..n].copy_from_slice(verts);
        let mut i = 0;
        while i < n {
            let d = sub(v[i], v[(i + 1) % n]);
            if dot(d, d).sqrt() < 1.0e-6 {
                v.copy_within(i + 1..n, i);
                n -= 1;
            } else {
                i += 1;
            }
        }
        if n < 3 {
            return Ok(());
        }
        writeln!(self.out, "p {n}")?;
        for p in &v[..n] {
            self.line("", p)?;
        }
        Ok(())
    }
}

/// Appends `v` as C's `printf("%g", v)`: six significant digits, scientific notation when
/// the exponent is below -4 or at least 6, trailing zeros (and a bare point) removed. Rust
/// rounds exact ties to even, as glibc does.
fn push_g(out: &mut String, tmp: &mut String, v: f64) {
    if v.is_nan() {
        out.push_str(if v.is_sign_negative() { "-nan" } else { "nan" });
        return;
    }
    if v.is_infinite() {
        out.push_str(if v < 0.0 { "-inf" } else { "inf" });
        return;
    }
    if v == 0.0 {
        out.push_str(if v.is_sign_negative() { "-0" } else { "0" });
        return;
    }
    tmp.clear();
    write!(tmp, "{v:.5e}").unwrap();
    let e = tmp.find('e').unwrap();
    let exp: i32 = tmp[e + 1..].parse().unwrap();
    if (-4..6).contains(&exp) {
        tmp.clear();
        write!(tmp, "{:.*}", (5 - exp) as usize, v).unwrap();
        out.push_str(strip_zeros(tmp));
    } else {
        out.push_str(strip_zeros(&tmp[..e]));
        let sign = if exp < 0 { '-' } else { '+' };
        write!(out, "e{sign}{:02}", exp.abs()).unwrap();
    }
}

fn strip_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

// ---------------------------------------------------------------------------------------
// Vectors and matrices (row vectors times matrices, as libvec).

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(v: &mut Vec3) {
    let d = dot(*v, *v).sqrt();
    if d > 0.0 {
        v.iter_mut().for_each(|c| *c /= d);
    }
}

fn identity() -> Matrix {
    let mut m = [[0.0; 4]; 4];
    (0..4).for_each(|i| m[i][i] = 1.0);
    m
}

/// Rotation about the Z axis (`axis` 2) or the Y axis (1).
fn rotate(axis: usize, angle: f64) -> Matrix {
    let (c, s) = (angle.cos(), angle.sin());
    let mut m = [[0.0; 4]; 4];
    match axis {
        1 => {
            m[1][1] = 1.0;
            m[0][0] = c;
            m[2][2] = c;
            m[2][0] = s;
            m[0][2] = -s;
        }
        2 => {
            m[2][2] = 1.0;
            m[0][0] = c;
            m[1][1] = c;
            m[0][1] = s;
            m[1][0] = -s;
        }
        _ => unreachable!("rotation about X is not needed"),
    }
    m[3][3] = 1.0;
    m
}

/// Rotation by `angle` about the unit vector `a`.
fn axis_rotate(a: Vec3, angle: f64) -> Matrix {
    let (c, s) = (angle.cos(), angle.sin());
    let omc = 1.0 - c;
    let [x, y, z] = a;
    [
        [
            x * x + (1.0 - x * x) * c,
            x * y * omc + z * s,
            x * z * omc - y * s,
            0.0,
        ],
        [
            x * y * omc - z * s,
            y * y + (1.0 - y * y) * c,
            y * z * omc + x * s,
            0.0,
        ],
        [
            x * z * omc + y * s,
            y * z * omc - x * s,
            z * z + (1.0 - z * z) * c,
            0.0,
        ],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn transform_vector(v: Vec3, m: &Matrix) -> Vec3 {
    let mut r = [0.0; 3];
    for (j, c) in r.iter_mut().enumerate() {
        *c = v[0] * m[0][j] + v[1] * m[1][j] + v[2] * m[2][j];
    }
    r
}

fn transform_coord(v: Vec4, m: &Matrix) -> Vec4 {
    let mut r = [0.0; 4];
    for (j, c) in r.iter_mut().enumerate() {
        *c = v[0] * m[0][j] + v[1] * m[1][j] + v[2] * m[2][j] + v[3] * m[3][j];
    }
    r
}

// ---------------------------------------------------------------------------------------
// mount

const MOUNTAIN_NO: i64 = 21;
const FRACTAL_DIMENSION: f64 = 2.2;
const CORNER: f64 = -1.0;
const WIDTH: f64 = 2.0;

/// The original database's hash of a grid point: faulty (it repeats), but it is what
/// defines the mountain. Shift counts are masked to six bits, as on x86-64.
fn hash_rand(a: i64, b: i64, size: u32) -> i64 {
    let shl = |x: i64, n: i64| (x as u64).wrapping_shl(n as u32);
    let s = size as i64;
    let h = shl(a, 23 - s)
        .wrapping_add(shl(b, 15 - s))
        .wrapping_add(shl(a, 7 - s));
    (h & 0xffff) as i64
}

/// A normal deviate from a seed (Numerical Recipes' GASDEV with a portable generator).
fn gauss_rand(seed: i64) -> f64 {
    const M1: i64 = 134456;
    const IA1: i64 = 8121;
    const IC1: i64 = 28411;
    let rm1 = 1.0 / M1 as f64;
    let mut ix2 = seed;
    loop {
        let ix1 = (IC1 + ix2 * IA1) % M1;
        ix2 = (IC1 + ix1 * IA1) % M1;
        let v1 = ix1 as f64 * 2.0 * rm1 - 1.0;
        let v2 = ix2 as f64 * 2.0 * rm1 - 1.0;
        let r = v1 * v1 + v2 * v2;
        if r < 1.0 {
            return v1 * (-2.0 * r.ln() / r).sqrt();
        }
    }
}

fn mount<W: Write>(nff: &mut Nff<W>, size: u32) -> io::Result<()> {
    nff.background([0.078, 0.361, 0.753])?;
    nff.viewpoint(
        [-1.6, 1.6, 1.7],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        45.0,
        0.01,
        (512, 512),
    )?;
    nff.light([-100.0, -100.0, 100.0])?;

    // A pyramid of four crystal spheres.
    nff.color([1.0, 1.0, 1.0], 0.0, 0.1, 0.1, 0.4, 6.7, 0.9, 1.5)?;
    let center = [-0.8, 0.8, 1.0, 0.17];
    let mut axis = [1.0, 1.0, 0.0];
    normalize(&mut axis);
    let angle = (-1.0f64 / 3.0).acos();
    let pt = [0.0, 0.0, center[3] * (3.0f64 / 2.0).sqrt()];
    nff.sphere([
        center[0] + pt[0],
        center[1] + pt[1],
        center[2] + pt[2],
        center[3],
    ])?;
    let new_pt = transform_vector(pt, &axis_rotate(axis, angle));
    for i in 0..3 {
        let mx = rotate(2, i as f64 * 2.0 * PI / 3.0);
        let s = transform_vector(new_pt, &mx);
        nff.sphere([
            s[0] + center[0],
            s[1] + center[1],
            s[2] + center[2],
            center[3],
        ])?;
    }

    // The mountain.
    nff.color([0.5, 0.45, 0.35], 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)?;
    let num_pts = 1i64 << size;
    let ratio = 2.0 / (2.0f64.ln() / (FRACTAL_DIMENSION - 1.0)).exp();
    let m = Mountain {
        size,
        fnum_pts: num_pts as f64,
        roughness: (ratio * ratio - 1.0).sqrt(),
    };
    m.grow(nff, num_pts, 0, 0, [0.0; 4])
}

struct Mountain {
    size: u32,
    fnum_pts: f64,
    roughness: f64,
}

impl Mountain {
    /// The square of `width` grid cells at (`x`, `y`) with corner heights `z` (lower left,
    /// lower right, upper right, upper left): two triangles for one cell, else four
    /// quarters after displacing the edge midpoints and the centre.
    fn grow<W: Write>(
        &self,
        nff: &mut Nff<W>,
        width: i64,
        x: i64,
        y: i64,
        z: [f64; 4],
    ) -> io::Result<()> {
        let [ll, lr, ur, ul] = z;
        let n = self.fnum_pts;
        if width == 1 {
            let l_x = CORNER + x as f64 * WIDTH / n;
            let r_x = CORNER + (x + 1) as f64 * WIDTH / n;
            let l_y = CORNER + y as f64 * WIDTH / n;
            let u_y = CORNER + (y + 1) as f64 * WIDTH / n;
            let corner = [
                [l_x, l_y, ll],
                [r_x, l_y, lr],
                [r_x, u_y, ur],
                [l_x, u_y, ul],
            ];
            nff.polygon(&[corner[0], corner[1], corner[2]])?;
            return nff.polygon(&[corner[2], corner[3], corner[0]]);
        }
        let half = width >> 1;
        let rise = half as f64 * WIDTH / n * self.roughness;
        let bump = |a: i64, b: i64| gauss_rand(MOUNTAIN_NO + hash_rand(a, b, self.size));
        let lower = (ll + lr) / 2.0 + rise * bump(x + half, y);
        let right = (lr + ur) / 2.0 + rise * bump(x + width, y + half);
        let upper = (ur + ul) / 2.0 + rise * bump(x + half, y + width);
        let left = (ul + ll) / 2.0 + rise * bump(x, y + half);
        // The SPD's own rounding of the square root of two: it shapes the mountain.
        #[allow(clippy::approx_constant)]
        let middle = (ll + lr + ur + ul) / 4.0 + 1.4142136 * rise * bump(x + half, y + half);
        self.grow(nff, half, x, y, [ll, lower, middle, left])?;
        self.grow(nff, half, x + half, y, [lower, lr, right, middle])?;
        self.grow(nff, half, x + half, y + half, [middle, right, ur, upper])?;
        self.grow(nff, half, x, y + half, [left, middle, upper, ul])
    }
}

// ---------------------------------------------------------------------------------------
// balls

fn balls<W: Write>(nff: &mut Nff<W>, size: u32) -> io::Result<()> {
    let radius = 1.0;
    nff.background([0.078, 0.361, 0.753])?;
    nff.viewpoint(
        [2.1, 1.3, 1.7],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        45.0,
        0.01,
        (512, 512),
    )?;
    nff.light([4.0, 3.0, 2.0])?;
    nff.light([1.0, -4.0, 4.0])?;
    nff.light([-3.0, 1.0, 5.0])?;

    // The floor, a closed loop of five vertices of which the last repeats the first.
    nff.color([1.0, 0.75, 0.33], 0.2, 0.8, 0.0, 0.0, 0.0, 0.0, 1.0)?;
    let (bx, by, bz) = (12.0 * radius, 12.0 * radius, -radius / 2.0);
    nff.polygon(&[
        [bx, by, bz],
        [-bx, by, bz],
        [-bx, -by, bz],
        [bx, -by, bz],
        [bx, by, bz],
    ])?;

    nff.color([1.0, 0.9, 0.7], 0.0, 0.5, 0.5, 0.5, 37.0, 0.0, 1.0)?;
    let flake = Flake {
        objset: objset(),
        size,
    };
    flake.output(
        nff,
        size,
        [0.0, 0.0, 0.0, radius / 2.0],
        [0.0, 0.0, 1.0, 1.0 / 3.0],
    )
}

/// The nine directions of the children around a parent pointing up +Z: three trios,
/// 120 degrees apart.
fn objset() -> [Vec4; 9] {
    let dist = 1.0 / 2.0f64.sqrt();
    let mut trio = [
        [dist, dist, 0.0, 0.0],
        [dist, 0.0, -dist, 0.0],
        [0.0, dist, -dist, 0.0],
    ];
    let mut axis = [1.0, -1.0, 0.0];
    normalize(&mut axis);
    let mx = axis_rotate(axis, (2.0 / 6.0f64.sqrt()).asin());
    for t in &mut trio {
        *t = transform_coord(*t, &mx);
    }
    let mut set = [[0.0; 4]; 9];
    for num_set in 0..3 {
        let mx = rotate(2, num_set as f64 * 2.0 * PI / 3.0);
        for (k, t) in trio.iter().enumerate() {
            set[num_set * 3 + k] = transform_coord(*t, &mx);
        }
    }
    set
}

struct Flake {
    objset: [Vec4; 9],
    size: u32,
}

impl Flake {
    /// The sphere `center` (radius in w), then, `depth` levels deep, its nine children
    /// around `dir` (w: the children's radius ratio).
    fn output<W: Write>(
        &self,
        nff: &mut Nff<W>,
        depth: u32,
        center: Vec4,
        dir: Vec4,
    ) -> io::Result<()> {
        debug_assert!(depth <= self.size);
        nff.sphere(center)?;
        if depth == 0 {
            return Ok(());
        }
        let mx = if dir[2] >= 0.9999 {
            identity()
        } else if dir[2] <= -0.9999 {
            rotate(1, PI)
        } else {
            let z_axis = [0.0, 0.0, 1.0];
            let d3 = [dir[0], dir[1], dir[2]];
            let mut axis = cross(z_axis, d3);
            normalize(&mut axis);
            axis_rotate(axis, dot(z_axis, d3).acos())
        };
        let scale = center[3] * (1.0 + dir[3]);
        for o in &self.objset {
            let mut child = transform_coord(*o, &mx);
            for k in 0..3 {
                child[k] = child[k] * scale + center[k];
            }
            child[3] = center[3] * dir[3];
            let mut child_dir = [0.0, 0.0, 0.0, dir[3]];
            for k in 0..3 {
                child_dir[k] = (child[k] - center[k]) / scale;
            }
            self.output(nff, depth - 1, child, child_dir)?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: spd mount|balls SIZE > out.nff";
    let (model, size) = match args.as_slice() {
        [name, s] => match (Model::parse(name), s.parse::<u32>()) {
            (Some(m), Ok(s)) if m.sizes().contains(&s) => (m, s),
            (Some(m), _) => {
                let r = m.sizes();
                eprintln!(
                    "{usage}\n{name} SIZE is {} to {}, not {s}",
                    r.start(),
                    r.end()
                );
                std::process::exit(2);
            }
            _ => {
                eprintln!("{usage}");
                std::process::exit(2);
            }
        },
        _ => {
            eprintln!("{usage}");
            std::process::exit(2);
        }
    };
    let stdout = io::stdout().lock();
    if let Err(e) = write_nff(model, size, io::BufWriter::with_capacity(1 << 20, stdout))
        && e.kind() != io::ErrorKind::BrokenPipe
    {
        eprintln!("spd: {e}");
        std::process::exit(1);
    }
}
