//! `gen_mesh`: writes triangle-mesh OBJ files (icospheres and heightfield terrains) for the
//! path tracer's tests and benchmarks.
//!
//! # Usage
//!
//! ```text
//! cargo run --release --example gen_mesh -- icosphere   --subdivisions N [--radius R] -o FILE.obj
//! cargo run --release --example gen_mesh -- icosphere   --triangles T    [--radius R] -o FILE.obj
//! cargo run --release --example gen_mesh -- heightfield --resolution N [--size S] [--height H] -o FILE.obj
//! cargo run --release --example gen_mesh -- heightfield --triangles T  [--size S] [--height H] -o FILE.obj
//! ```
//!
//! Both shapes also take `--decimals D` (default 6): the number of decimal places written for
//! positions, normals and UVs (trailing zeros are trimmed, so `0.500000` is written `0.5`).
//!
//! * `icosphere --subdivisions N`: a regular icosahedron (20 faces) whose triangles are each split
//!   into 4 per level, with midpoints shared between neighbouring triangles and pushed out onto
//!   the sphere. `V = 10 * 4^N + 2` vertices, `F = 20 * 4^N` triangles, `N <= 10`.
//! * `icosphere --triangles T`: the smallest level with at least `T` triangles
//!   (`--triangles 1000000` gives level 8 = 1,310,720 triangles).
//! * `heightfield --resolution N`: an `N x N` grid of quads over `[-S/2, S/2]^2` in the XZ plane
//!   (default `S = 4`), with `y = H * f(x/S, z/S)` (default `H = 0.4`) where `f` is a fixed sum
//!   of five plane sine waves with `|f| <= 1`. `(N + 1)^2` vertices, `2 * N^2` triangles.
//! * `heightfield --triangles T`: `N = round(sqrt(T / 2))`, the resolution whose count is closest.
//!
//! Every run self-checks the mesh as it will be read back (positions rounded to `--decimals`)
//! and fails without writing if a check does not hold. Icosphere: vertex and face counts, closed
//! consistently oriented 2-manifold with Euler characteristic `V - E + F = 2`, every vertex at
//! distance `R` within `1e-5 * R`, and every face counter-clockwise seen from outside
//! (`dot(cross(b - a, c - a), a + b + c) > 0`). Heightfield: counts, consistently oriented disk
//! (`V - E + F = 1`, `4N` boundary edges), and every face and vertex normal pointing up (`y > 0`).
//!
//! One summary line goes to stdout: counts, file size, time per phase, and peak memory.
//!
//! # Output format and conventions
//!
//! Plain OBJ: `#` comment header, then all `v x y z`, all `vn x y z`, all `vt u v`, then
//! `f a/a/a b/b/b c/c/c` (1-based; each vertex has its own position, normal and UV, so the three
//! indices are equal). Faces are counter-clockwise seen from the side the normal points to
//! (right-hand rule), Y is up.
//!
//! * Icosphere normals are the unit position. UVs are longitude/latitude:
//!   `u = 0.5 - atan2(z, x) / (2 pi)`, `v = 0.5 + asin(y / R) / pi`. So `v = 0` at the south pole
//!   and `v = 1` at the north pole (OBJ/OpenGL `v`-up convention), and `u` grows to the right
//!   seen from outside, i.e. a texture is not mirrored (`dP/du x dP/dv` points outward). The
//!   seam (`u = 0` and `u = 1`) runs along `z = 0, x < 0`. Known, accepted artifacts: vertices are
//!   not duplicated on the seam, so the one column of triangles that straddles it interpolates
//!   `u` from near 1 back to near 0 (the whole texture squeezed, mirrored, into that strip); and
//!   the two pole vertices (present from level 1 on) get `u = 0.5`, so the triangles around a
//!   pole show a pinched texture.
//! * Heightfield normals come from the analytic gradient of the height function,
//!   `normalize(-dy/dx, 1, -dy/dz)`. UVs are the grid coordinates `u = i / N` (grows with `x`),
//!   `v = 1 - j / N` (grows towards `-z`), which is not mirrored seen from above.

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};
use std::fs::File;
use std::hash::{BuildHasherDefault, Hasher};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, ensure, Context, Result};
use clap::{ArgGroup, Args, Parser, Subcommand};
use glam::{DVec2, DVec3};

/// Largest icosphere subdivision level accepted (20 * 4^10 = 20,971,520 triangles).
const MAX_SUBDIVISIONS: u32 = 10;
/// Largest heightfield resolution accepted (2 * 4096^2 = 33,554,432 triangles).
const MAX_RESOLUTION: u32 = 4096;
/// Largest magnitude accepted for `--radius`, `--size` and `--height`, so that a coordinate
/// times `10^decimals` always fits the integer formatter.
const MAX_EXTENT: f64 = 1e6;
/// Relative tolerance of the icosphere radius check and the unit-normal checks.
const TOLERANCE: f64 = 1e-5;

#[derive(Parser)]
#[command(
    name = "gen_mesh",
    about = "Generate triangle-mesh OBJ files (icosphere, heightfield) for tests and benchmarks"
)]
struct Cli {
    #[command(subcommand)]
    shape: Shape,
}

#[derive(Subcommand)]
enum Shape {
    /// Subdivided icosahedron projected onto a sphere centred at the origin.
    Icosphere(IcosphereArgs),
    /// N x N grid of quads (two triangles each) in the XZ plane, displaced along Y.
    Heightfield(HeightfieldArgs),
}

#[derive(Args)]
#[command(group(ArgGroup::new("detail").required(true).args(["subdivisions", "triangles"])))]
struct IcosphereArgs {
    /// Subdivision levels: each level splits every triangle into 4 (F = 20 * 4^N).
    #[arg(long)]
    subdivisions: Option<u32>,
    /// Target triangle count: uses the smallest level with at least this many triangles.
    #[arg(long)]
    triangles: Option<u64>,
    /// Sphere radius.
    #[arg(long, default_value_t = 1.0)]
    radius: f64,
    #[command(flatten)]
    out: OutputArgs,
}

#[derive(Args)]
#[command(group(ArgGroup::new("detail").required(true).args(["resolution", "triangles"])))]
struct HeightfieldArgs {
    /// Quads per side (F = 2 * N^2).
    #[arg(long)]
    resolution: Option<u32>,
    /// Target triangle count: uses the resolution whose 2 * N^2 is closest.
    #[arg(long)]
    triangles: Option<u64>,
    /// Side length of the square patch, centred at the origin.
    #[arg(long, default_value_t = 4.0)]
    size: f64,
    /// Peak height: y ranges within [-H, H] (negative H flips the terrain upside down).
    #[arg(long, default_value_t = 0.4, allow_negative_numbers = true)]
    height: f64,
    #[command(flatten)]
    out: OutputArgs,
}

#[derive(Args)]
struct OutputArgs {
    /// OBJ file to write (parent folders are created).
    #[arg(short, long)]
    output: PathBuf,
    /// Decimal places written for positions, normals and UVs (trailing zeros trimmed).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=9))]
    decimals: u32,
}

/// Indexed triangle mesh with one position, normal and UV per vertex.
struct Mesh {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    uvs: Vec<DVec2>,
    faces: Vec<[u32; 3]>,
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.shape {
        Shape::Icosphere(args) => run_icosphere(&args),
        Shape::Heightfield(args) => run_heightfield(&args),
    }
}

/// Wall-clock time of each phase of one run.
struct Timings {
    generate: Duration,
    check: Duration,
    write: Duration,
}

/// Resolves the subdivision level, builds, checks and writes an icosphere, and prints the summary.
fn run_icosphere(args: &IcosphereArgs) -> Result<()> {
    let radius = args.radius;
    ensure!(
        radius.is_finite() && radius > 0.0 && radius <= MAX_EXTENT,
        "--radius must be in (0, {MAX_EXTENT}], got {radius}"
    );
    let (subdivisions, requested) = match (args.subdivisions, args.triangles) {
        (Some(n), _) => (n, String::new()),
        (None, Some(t)) => (
            subdivisions_for_triangles(t)?,
            format!(" (requested >= {t})"),
        ),
        (None, None) => unreachable!("clap requires --subdivisions or --triangles"),
    };
    ensure!(
        subdivisions <= MAX_SUBDIVISIONS,
        "--subdivisions must be at most {MAX_SUBDIVISIONS}, got {subdivisions}"
    );
    let fmt = FixedFormat::new(args.out.decimals);

    let start = Instant::now();
    let mesh = icosphere(subdivisions, radius);
    let generated = Instant::now();
    check_icosphere(&mesh, subdivisions, radius, &fmt).context("icosphere self-check failed")?;
    let checked = Instant::now();
    let header = [
        format!("gen_mesh icosphere --subdivisions {subdivisions} --radius {radius}"),
        "uv: u = 0.5 - atan2(z, x) / (2 pi), v = 0.5 + asin(y / R) / pi (seam at z = 0, x < 0)"
            .to_string(),
    ];
    let bytes = write_obj(&args.out.output, &header, &mesh, &fmt)?;
    let written = Instant::now();

    let timings = Timings {
        generate: generated - start,
        check: checked - generated,
        write: written - checked,
    };
    let what = format!("icosphere subdivisions={subdivisions} radius={radius}");
    print_summary(&what, &requested, &args.out.output, &mesh, bytes, &timings);
    Ok(())
}

/// Resolves the grid resolution, builds, checks and writes a heightfield, and prints the summary.
fn run_heightfield(args: &HeightfieldArgs) -> Result<()> {
    let (size, height) = (args.size, args.height);
    ensure!(
        size.is_finite() && size > 0.0 && size <= MAX_EXTENT,
        "--size must be in (0, {MAX_EXTENT}], got {size}"
    );
    ensure!(
        height.is_finite() && height.abs() <= MAX_EXTENT,
        "--height must be finite with |H| <= {MAX_EXTENT}, got {height}"
    );
    let (resolution, requested) = match (args.resolution, args.triangles) {
        (Some(n), _) => (n, String::new()),
        (None, Some(t)) => (resolution_for_triangles(t)?, format!(" (requested ~{t})")),
        (None, None) => unreachable!("clap requires --resolution or --triangles"),
    };
    ensure!(
        (1..=MAX_RESOLUTION).contains(&resolution),
        "--resolution must be in 1..={MAX_RESOLUTION}, got {resolution}"
    );
    let fmt = FixedFormat::new(args.out.decimals);

    let start = Instant::now();
    let mesh = heightfield(resolution, size, height);
    let generated = Instant::now();
    check_heightfield(&mesh, resolution, &fmt).context("heightfield self-check failed")?;
    let checked = Instant::now();
    let header = [
        format!("gen_mesh heightfield --resolution {resolution} --size {size} --height {height}"),
        "uv: u = i / N (along +x), v = 1 - j / N (along -z)".to_string(),
    ];
    let bytes = write_obj(&args.out.output, &header, &mesh, &fmt)?;
    let written = Instant::now();

    let timings = Timings {
        generate: generated - start,
        check: checked - generated,
        write: written - checked,
    };
    let what = format!("heightfield resolution={resolution} size={size} height={height}");
    print_summary(&what, &requested, &args.out.output, &mesh, bytes, &timings);
    Ok(())
}

/// Prints the one-line summary of a run to stdout.
fn print_summary(what: &str, requested: &str, path: &Path, mesh: &Mesh, bytes: u64, t: &Timings) {
    let total = t.generate + t.check + t.write;
    let rss = peak_rss_kib()
        .map(|kib| format!(", peak RSS {:.1} MiB", kib as f64 / 1024.0))
        .unwrap_or_default();
    println!(
        "{what}: {} vertices, {} triangles{requested}, wrote {} ({bytes} bytes, {:.2} MiB), \
         self-check ok, {:.3} s (generate {:.3} s, check {:.3} s, write {:.3} s){rss}",
        mesh.positions.len(),
        mesh.faces.len(),
        path.display(),
        bytes as f64 / (1024.0 * 1024.0),
        total.as_secs_f64(),
        t.generate.as_secs_f64(),
        t.check.as_secs_f64(),
        t.write.as_secs_f64(),
    );
}

/// Peak resident set size of this process in KiB (`VmHWM` on Linux; `None` elsewhere).
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

// ---------------------------------------------------------------------------------------------
// Icosphere
// ---------------------------------------------------------------------------------------------

/// Smallest subdivision level whose triangle count `20 * 4^N` is at least `triangles`.
fn subdivisions_for_triangles(triangles: u64) -> Result<u32> {
    (0..=MAX_SUBDIVISIONS)
        .find(|&n| 20 * 4u64.pow(n) >= triangles)
        .with_context(|| {
            format!(
                "--triangles {triangles} needs more than {MAX_SUBDIVISIONS} subdivisions \
                 (at most {} triangles)",
                20 * 4u64.pow(MAX_SUBDIVISIONS)
            )
        })
}

/// Unit-radius regular icosahedron: 12 vertices `(0, ±1, ±phi)` and their cyclic permutations
/// (normalized), and 20 faces wound counter-clockwise seen from outside.
fn icosahedron() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let positions = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .into_iter()
    .map(|(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let faces = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (positions, faces)
}

/// Fast hasher for the midpoint cache, whose keys are packed `u64` vertex pairs
/// (a splitmix64-style finalizer: every input bit affects the high and the low output bits).
#[derive(Default)]
struct EdgeHasher(u64);

impl Hasher for EdgeHasher {
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        h ^ (h >> 31)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
    }

    fn write_u64(&mut self, n: u64) {
        self.0 = n;
    }
}

/// Order-independent key of the edge between vertices `a` and `b`.
fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// One subdivision level on the unit sphere: splits each triangle `(a, b, c)` into
/// `(a, ab, ca)`, `(b, bc, ab)`, `(c, ca, bc)`, `(ab, bc, ca)`, which keeps its winding. Each
/// edge's midpoint is created once (cached by edge, so the two triangles sharing an edge share
/// the new vertex), normalized onto the unit sphere, and appended to `positions`.
fn subdivide(positions: &mut Vec<DVec3>, faces: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let edges = faces.len() * 3 / 2;
    positions.reserve(edges);
    let mut cache: HashMap<u64, u32, BuildHasherDefault<EdgeHasher>> =
        HashMap::with_capacity_and_hasher(edges, BuildHasherDefault::default());
    let mut midpoint = |a: u32, b: u32| -> u32 {
        *cache.entry(edge_key(a, b)).or_insert_with(|| {
            let p = (positions[a as usize] + positions[b as usize]).normalize();
            positions.push(p);
            (positions.len() - 1) as u32
        })
    };
    let mut out = Vec::with_capacity(faces.len() * 4);
    for &[a, b, c] in faces {
        let ab = midpoint(a, b);
        let bc = midpoint(b, c);
        let ca = midpoint(c, a);
        out.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    out
}

/// Longitude/latitude UV of a unit direction: `u = 0.5 - atan2(z, x) / (2 pi)`,
/// `v = 0.5 + asin(y) / pi` (see the module docs for the seam and pole artifacts).
fn sphere_uv(n: DVec3) -> DVec2 {
    // `+ 0.0` turns a -0.0 into +0.0 so that seam vertices (z = 0, x < 0) always get u = 0.
    let u = 0.5 - (n.z + 0.0).atan2(n.x) / TAU;
    let v = 0.5 + n.y.clamp(-1.0, 1.0).asin() / PI;
    DVec2::new(u, v)
}

/// Icosphere of the given level and radius: subdivides the unit icosahedron `subdivisions`
/// times, then derives per-vertex normal (unit position), UV, and position (`radius * normal`).
fn icosphere(subdivisions: u32, radius: f64) -> Mesh {
    let (mut unit, mut faces) = icosahedron();
    for _ in 0..subdivisions {
        faces = subdivide(&mut unit, &faces);
    }
    let positions = unit.iter().map(|&n| n * radius).collect();
    let uvs = unit.iter().map(|&n| sphere_uv(n)).collect();
    Mesh {
        positions,
        normals: unit,
        uvs,
        faces,
    }
}

/// Checks an icosphere as it will be read back from the file (positions and normals rounded to
/// the output precision): exact counts, closed and consistently oriented with
/// `V - E + F = 2`, every vertex at distance `radius` within `TOLERANCE * radius`, every face
/// counter-clockwise seen from outside, unit normals, and UVs within `[0, 1]`.
fn check_icosphere(mesh: &Mesh, subdivisions: u32, radius: f64, fmt: &FixedFormat) -> Result<()> {
    let (v, f) = (mesh.positions.len(), mesh.faces.len());
    let expected_v = 10 * 4usize.pow(subdivisions) + 2;
    let expected_f = 20 * 4usize.pow(subdivisions);
    ensure!(
        v == expected_v,
        "{v} vertices, expected 10 * 4^N + 2 = {expected_v}"
    );
    ensure!(
        f == expected_f,
        "{f} faces, expected 20 * 4^N = {expected_f}"
    );

    let edges = edge_stats(&mesh.faces, v)?;
    ensure!(
        edges.boundary == 0,
        "{} boundary edges, expected a closed surface",
        edges.boundary
    );
    let euler = v as i64 - edges.edges as i64 + f as i64;
    ensure!(
        euler == 2,
        "V - E + F = {v} - {} + {f} = {euler}, expected 2",
        edges.edges
    );

    for (i, &p) in mesh.positions.iter().enumerate() {
        let r = fmt.round_vec(p).length();
        ensure!(
            (r - radius).abs() <= TOLERANCE * radius,
            "vertex {i} is at distance {r} from the centre, expected {radius} \
             (try a larger --decimals)"
        );
    }

    for (k, &[a, b, c]) in mesh.faces.iter().enumerate() {
        let pa = fmt.round_vec(mesh.positions[a as usize]);
        let pb = fmt.round_vec(mesh.positions[b as usize]);
        let pc = fmt.round_vec(mesh.positions[c as usize]);
        let outward = (pb - pa).cross(pc - pa).dot(pa + pb + pc);
        ensure!(
            outward > 0.0,
            "face {k} ({a}, {b}, {c}) is clockwise seen from outside or degenerate"
        );
    }

    check_attributes(mesh, fmt)
}

// ---------------------------------------------------------------------------------------------
// Heightfield
// ---------------------------------------------------------------------------------------------

/// Resolution `N` whose triangle count `2 * N^2` is closest to `triangles` (at least 1).
fn resolution_for_triangles(triangles: u64) -> Result<u32> {
    let n = ((triangles as f64 / 2.0).sqrt().round() as u64).max(1);
    // Round-to-nearest on sqrt can miss the closest square by one; compare the neighbours.
    let distance = |n: u64| (2 * n * n).abs_diff(triangles);
    let n = [n.saturating_sub(1).max(1), n, n + 1]
        .into_iter()
        .min_by_key(|&n| distance(n))
        .unwrap_or(n);
    ensure!(
        n <= u64::from(MAX_RESOLUTION),
        "--triangles {triangles} needs a resolution above {MAX_RESOLUTION} \
         (at most {} triangles)",
        2 * u64::from(MAX_RESOLUTION).pow(2)
    );
    Ok(n as u32)
}

/// Plane waves of the terrain: `(amplitude, cycles along s, cycles along t, phase)`, each term
/// `amplitude * sin(2 pi (ks * s + kt * t) + phase)`. Amplitudes sum to 1, so `|f| <= 1`.
const WAVES: [(f64, f64, f64, f64); 5] = [
    (0.40, 0.9, 0.6, 0.3),
    (0.25, -1.3, 1.7, 1.9),
    (0.15, 2.9, 0.7, 4.1),
    (0.12, 1.1, -3.6, 2.5),
    (0.08, 5.3, 4.4, 0.9),
];

/// Terrain function `f(s, t)` on normalized coordinates `s = x / S`, `t = z / S` in
/// `[-0.5, 0.5]`, and its analytic gradient `(df/ds, df/dt)`.
fn terrain(s: f64, t: f64) -> (f64, DVec2) {
    let mut f = 0.0;
    let mut grad = DVec2::ZERO;
    for (amp, ks, kt, phase) in WAVES {
        let arg = TAU * (ks * s + kt * t) + phase;
        f += amp * arg.sin();
        grad += amp * TAU * arg.cos() * DVec2::new(ks, kt);
    }
    (f, grad)
}

/// Heightfield of `resolution x resolution` quads over `[-size/2, size/2]^2` in XZ.
/// Vertex `(i, j)` (index `j * (N + 1) + i`) sits at `x = -S/2 + S i / N`, `z = -S/2 + S j / N`,
/// `y = H f(x / S, z / S)`; its normal is `normalize(-dy/dx, 1, -dy/dz)` from the analytic
/// gradient and its UV is `(i / N, 1 - j / N)`. Quad `(i, j)` with corners `a = (i, j)`,
/// `b = (i + 1, j)`, `c = (i, j + 1)`, `d = (i + 1, j + 1)` becomes triangles `(a, c, b)` and
/// `(b, c, d)`, both counter-clockwise seen from above (`cross(z, x) = +y`).
fn heightfield(resolution: u32, size: f64, height: f64) -> Mesh {
    let n = resolution as usize;
    let side = n + 1;
    let mut positions = Vec::with_capacity(side * side);
    let mut normals = Vec::with_capacity(side * side);
    let mut uvs = Vec::with_capacity(side * side);
    for j in 0..side {
        for i in 0..side {
            let (gu, gv) = (i as f64 / n as f64, j as f64 / n as f64);
            let (s, t) = (gu - 0.5, gv - 0.5);
            let (f, grad) = terrain(s, t);
            // d(H f(x/S, z/S))/dx = (H / S) df/ds, and likewise for z.
            let slope = grad * (height / size);
            positions.push(DVec3::new(s * size, height * f, t * size));
            normals.push(DVec3::new(-slope.x, 1.0, -slope.y).normalize());
            uvs.push(DVec2::new(gu, 1.0 - gv));
        }
    }
    let mut faces = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let a = (j * side + i) as u32;
            let b = a + 1;
            let c = a + side as u32;
            let d = c + 1;
            faces.push([a, c, b]);
            faces.push([b, c, d]);
        }
    }
    Mesh {
        positions,
        normals,
        uvs,
        faces,
    }
}

/// Checks a heightfield as it will be read back: exact counts, a consistently oriented disk
/// (`4N` boundary edges, `V - E + F = 1`), every face normal and vertex normal pointing up
/// (`y > 0`), unit normals, and UVs within `[0, 1]`.
fn check_heightfield(mesh: &Mesh, resolution: u32, fmt: &FixedFormat) -> Result<()> {
    let n = resolution as usize;
    let (v, f) = (mesh.positions.len(), mesh.faces.len());
    ensure!(v == (n + 1) * (n + 1), "{v} vertices, expected (N + 1)^2");
    ensure!(f == 2 * n * n, "{f} faces, expected 2 N^2");

    let edges = edge_stats(&mesh.faces, v)?;
    ensure!(
        edges.boundary == 4 * n,
        "{} boundary edges, expected 4 N = {}",
        edges.boundary,
        4 * n
    );
    let euler = v as i64 - edges.edges as i64 + f as i64;
    ensure!(euler == 1, "V - E + F = {euler}, expected 1 for a disk");

    for (k, &[a, b, c]) in mesh.faces.iter().enumerate() {
        let pa = fmt.round_vec(mesh.positions[a as usize]);
        let pb = fmt.round_vec(mesh.positions[b as usize]);
        let pc = fmt.round_vec(mesh.positions[c as usize]);
        let normal = (pb - pa).cross(pc - pa);
        ensure!(normal.y > 0.0, "face {k} ({a}, {b}, {c}) does not face up");
    }
    for (i, &nrm) in mesh.normals.iter().enumerate() {
        ensure!(
            fmt.round_vec(nrm).y > 0.0,
            "vertex {i} normal {nrm} does not point up"
        );
    }

    check_attributes(mesh, fmt)
}

// ---------------------------------------------------------------------------------------------
// Shared checks
// ---------------------------------------------------------------------------------------------

/// Edge counts of an indexed triangle mesh.
struct EdgeStats {
    /// Distinct undirected edges.
    edges: usize,
    /// Edges used by exactly one face.
    boundary: usize,
}

/// Counts the undirected and boundary edges of `faces` after checking that every index is below
/// `vertex_count`, no face repeats a vertex, every edge is shared by at most two faces
/// (manifold), and the two faces sharing an edge traverse it in opposite directions (consistent
/// winding). Works by sorting one packed `u64` per face edge: `(min << 32) | (max << 1) | dir`,
/// so the (at most two) uses of an edge end up next to each other.
fn edge_stats(faces: &[[u32; 3]], vertex_count: usize) -> Result<EdgeStats> {
    ensure!(
        vertex_count < 1 << 31,
        "too many vertices ({vertex_count}) for the edge check"
    );
    let mut keys = Vec::with_capacity(faces.len() * 3);
    for (k, face) in faces.iter().enumerate() {
        ensure!(
            face.iter().all(|&i| (i as usize) < vertex_count),
            "face {k} {face:?} has an index >= {vertex_count}"
        );
        let [a, b, c] = *face;
        ensure!(
            a != b && b != c && c != a,
            "face {k} {face:?} repeats a vertex"
        );
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let dir = u64::from(p > q);
            let (lo, hi) = if p < q { (p, q) } else { (q, p) };
            keys.push((u64::from(lo) << 32) | (u64::from(hi) << 1) | dir);
        }
    }
    keys.sort_unstable();

    let (mut edges, mut boundary) = (0, 0);
    for run in keys.chunk_by(|x, y| x >> 1 == y >> 1) {
        let (lo, hi) = (run[0] >> 32, (run[0] >> 1) & 0x7fff_ffff);
        match run {
            [_] => boundary += 1,
            [x, y] if x != y => {}
            [_, _] => bail!("edge ({lo}, {hi}) is traversed twice in the same direction"),
            _ => bail!("edge ({lo}, {hi}) is shared by {} faces", run.len()),
        }
        edges += 1;
    }
    Ok(EdgeStats { edges, boundary })
}

/// Checks that all attributes are finite, normals are unit length within `TOLERANCE` after
/// rounding, and UVs lie in `[0, 1]`.
fn check_attributes(mesh: &Mesh, fmt: &FixedFormat) -> Result<()> {
    ensure!(
        mesh.normals.len() == mesh.positions.len() && mesh.uvs.len() == mesh.positions.len(),
        "attribute counts differ"
    );
    for (i, ((p, nrm), uv)) in mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .zip(&mesh.uvs)
        .enumerate()
    {
        ensure!(
            p.is_finite() && nrm.is_finite() && uv.is_finite(),
            "vertex {i} has a non-finite attribute"
        );
        let len = fmt.round_vec(*nrm).length();
        ensure!(
            (len - 1.0).abs() <= TOLERANCE,
            "vertex {i} normal has length {len} (try a larger --decimals)"
        );
        ensure!(
            (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y),
            "vertex {i} UV {uv} outside [0, 1]"
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// OBJ writing
// ---------------------------------------------------------------------------------------------

/// Fixed-point decimal formatter: rounds to `decimals` places via an integer (no `fmt`
/// machinery), writes the digits itoa-style, and trims trailing fractional zeros. `-0` is
/// written as `0`.
struct FixedFormat {
    decimals: u32,
    /// `10^decimals` as an integer, splitting the scaled value into integer and fraction.
    pow: u64,
    /// `10^decimals` as a float, scaling values before rounding.
    scale: f64,
}

impl FixedFormat {
    fn new(decimals: u32) -> Self {
        let pow = 10u64.pow(decimals);
        Self {
            decimals,
            pow,
            scale: pow as f64,
        }
    }

    /// The value a reader gets back from the text written for `x` (up to float parsing).
    fn round(&self, x: f64) -> f64 {
        (x * self.scale).round() / self.scale
    }

    /// [`Self::round`] for each component.
    fn round_vec(&self, v: DVec3) -> DVec3 {
        DVec3::new(self.round(v.x), self.round(v.y), self.round(v.z))
    }

    /// Appends `x` rounded to `decimals` places, e.g. `-1.25`, `0.5`, `3`.
    fn push(&self, buf: &mut Vec<u8>, x: f64) {
        // Inputs are bounded by MAX_EXTENT, so |x| * 10^9 is far below i64::MAX.
        let q = (x * self.scale).round() as i64;
        if q == 0 {
            buf.push(b'0');
            return;
        }
        if q < 0 {
            buf.push(b'-');
        }
        let m = q.unsigned_abs();
        push_uint(buf, m / self.pow);
        let mut frac = m % self.pow;
        if frac != 0 {
            let mut digits = self.decimals as usize;
            while frac.is_multiple_of(10) {
                frac /= 10;
                digits -= 1;
            }
            buf.push(b'.');
            let start = buf.len();
            buf.resize(start + digits, b'0');
            for slot in buf[start..].iter_mut().rev() {
                *slot = b'0' + (frac % 10) as u8;
                frac /= 10;
            }
        }
    }
}

/// Appends the decimal digits of `n` (itoa-style, no allocation).
fn push_uint(buf: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    buf.extend_from_slice(&digits[i..]);
}

/// Writes `mesh` as OBJ to `path` (creating parent folders): `# header` lines and counts, then
/// `v`, `vn`, `vt` and `f a/a/a b/b/b c/c/c` lines. Each line is formatted into a reused byte
/// buffer and handed to a 1 MiB `BufWriter`. Returns the file size in bytes.
fn write_obj(path: &Path, header: &[String], mesh: &Mesh, fmt: &FixedFormat) -> Result<u64> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut out = BufWriter::with_capacity(1 << 20, file);
    let io =
        |e: std::io::Error| anyhow::Error::new(e).context(format!("writing {}", path.display()));

    for line in header {
        writeln!(out, "# {line}").map_err(io)?;
    }
    writeln!(
        out,
        "# vertices {} triangles {}",
        mesh.positions.len(),
        mesh.faces.len()
    )
    .map_err(io)?;

    let mut line = Vec::with_capacity(128);
    let mut vec3_lines = |out: &mut BufWriter<File>, tag: &[u8], values: &[DVec3]| {
        for v in values {
            line.clear();
            line.extend_from_slice(tag);
            for c in [v.x, v.y, v.z] {
                line.push(b' ');
                fmt.push(&mut line, c);
            }
            line.push(b'\n');
            out.write_all(&line)?;
        }
        std::io::Result::Ok(())
    };
    vec3_lines(&mut out, b"v", &mesh.positions).map_err(io)?;
    vec3_lines(&mut out, b"vn", &mesh.normals).map_err(io)?;

    for uv in &mesh.uvs {
        line.clear();
        line.extend_from_slice(b"vt ");
        fmt.push(&mut line, uv.x);
        line.push(b' ');
        fmt.push(&mut line, uv.y);
        line.push(b'\n');
        out.write_all(&line).map_err(io)?;
    }

    for face in &mesh.faces {
        line.clear();
        line.push(b'f');
        for &i in face {
            let obj_index = u64::from(i) + 1;
            line.push(b' ');
            push_uint(&mut line, obj_index);
            line.push(b'/');
            push_uint(&mut line, obj_index);
            line.push(b'/');
            push_uint(&mut line, obj_index);
        }
        line.push(b'\n');
        out.write_all(&line).map_err(io)?;
    }

    let file = out.into_inner().map_err(|e| io(e.into_error()))?;
    Ok(file.metadata().map_err(io)?.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_levels_pass_self_check() {
        let fmt = FixedFormat::new(6);
        for n in 0..=4 {
            let mesh = icosphere(n, 2.5);
            check_icosphere(&mesh, n, 2.5, &fmt).unwrap();
        }
    }

    #[test]
    fn heightfield_passes_self_check() {
        let fmt = FixedFormat::new(6);
        for n in [1, 2, 24] {
            check_heightfield(&heightfield(n, 4.0, 0.4), n, &fmt).unwrap();
        }
    }

    #[test]
    fn check_rejects_flipped_face() {
        let fmt = FixedFormat::new(6);
        let mut mesh = icosphere(1, 1.0);
        mesh.faces[3].swap(1, 2);
        assert!(check_icosphere(&mesh, 1, 1.0, &fmt).is_err());
    }

    #[test]
    fn triangle_targets() {
        assert_eq!(subdivisions_for_triangles(1).unwrap(), 0);
        assert_eq!(subdivisions_for_triangles(1280).unwrap(), 3);
        assert_eq!(subdivisions_for_triangles(1281).unwrap(), 4);
        assert_eq!(subdivisions_for_triangles(1_000_000).unwrap(), 8);
        assert_eq!(resolution_for_triangles(1152).unwrap(), 24);
        assert_eq!(resolution_for_triangles(1_000_000).unwrap(), 707);
        assert_eq!(resolution_for_triangles(0).unwrap(), 1);
    }

    #[test]
    fn fixed_format() {
        let fmt = FixedFormat::new(6);
        let text = |x: f64| {
            let mut buf = Vec::new();
            fmt.push(&mut buf, x);
            String::from_utf8(buf).unwrap()
        };
        assert_eq!(text(0.0), "0");
        assert_eq!(text(-0.0000001), "0");
        assert_eq!(text(1.0), "1");
        assert_eq!(text(0.5), "0.5");
        assert_eq!(text(-2.25), "-2.25");
        assert_eq!(text(0.1234567), "0.123457");
        assert_eq!(text(-12.000001), "-12.000001");
        assert_eq!(text(0.000042), "0.000042");
    }
}
