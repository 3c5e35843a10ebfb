//! Reading OBJ meshes on every core: the file is cut into chunks at line ends, the chunks are
//! parsed in parallel and joined in file order.
//!
//! Only the common form of a mesh file is read this way: `v x y z`, `vt`, `vn` and `f` lines
//! of three corners or more, every corner of the same form (`v`, `v/vt`, `v//vn` or
//! `v/vt/vn`) with its texture and normal indices equal to its position index, object and
//! group names only before the first face, and the lines `tobj` ignores (comments, `s`,
//! `mtllib`, `usemtl`). For anything else (relative indices, vertex colours, lines,
//! several groups of faces, an index out of range, a number that does not parse, text
//! that is not UTF-8) [`parse`] returns `None` and the caller reads the file with `tobj`,
//! which reports the errors. Where it answers, the result is the mesh `tobj` reads
//! (`single_index`, triangulated, all models merged): vertices numbered in the order the
//! faces first use them, unused ones left out, polygons split into fans.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Bytes per chunk parsed as one task.
const CHUNK_BYTES: usize = 1 << 18;

/// Positions, texture coordinates, normals and triangle corners (0-based position indices)
/// of one chunk, in file order.
#[derive(Default)]
struct Chunk {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    corners: Vec<u32>,
    /// The corner form of every face so far: whether corners name a texture coordinate and a
    /// normal (`None` before the first face).
    form: Option<(bool, bool)>,
    /// An object or group name line, and whether one came after a face of this chunk.
    named: bool,
    named_after_face: bool,
}

/// The mesh in `bytes`, read in parallel, or `None` for a file outside the form above.
pub(super) fn parse(bytes: &[u8]) -> Option<super::MeshData> {
    parse_in_chunks(bytes, CHUNK_BYTES)
}

fn parse_in_chunks(bytes: &[u8], chunk_bytes: usize) -> Option<super::MeshData> {
    let chunks: Vec<Chunk> = split_at_lines(bytes, chunk_bytes)
        .par_iter()
        .map(|part| parse_chunk(std::str::from_utf8(part).ok()?))
        .collect::<Option<_>>()?;
    // One form for all faces; names only before the first face.
    let mut form = None;
    for c in &chunks {
        if c.named_after_face || (c.named && form.is_some()) {
            return None;
        }
        if let Some(f) = c.form {
            if form.is_some_and(|g| g != f) {
                return None;
            }
            form = Some(f);
        }
    }
    let (has_uv, has_normal) = form?;
    let positions = concat(chunks.iter().map(|c| &c.positions[..]).collect());
    let normals = concat(chunks.iter().map(|c| &c.normals[..]).collect());
    let uvs = concat(chunks.iter().map(|c| &c.uvs[..]).collect());
    // `tobj` checks a corner's texture coordinate and normal only when the file has some.
    let limit = [
        Some(positions.len()),
        (has_uv && !uvs.is_empty()).then_some(uvs.len()),
        (has_normal && !normals.is_empty()).then_some(normals.len()),
    ]
    .into_iter()
    .flatten()
    .min()?;
    if chunks
        .par_iter()
        .any(|c| c.corners.iter().any(|&v| v as usize >= limit))
    {
        return None;
    }
    let (used, indices) = number_by_first_use(&chunks, positions.len());
    drop(chunks);
    let d3 = |p: [f32; 3]| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    let gather3 = |all: &[[f32; 3]]| used.par_iter().map(|&v| d3(all[v as usize])).collect();
    // Normals and texture coordinates for every vertex or none (as `load_obj` merges models).
    let with_uv = has_uv && !uvs.is_empty();
    let with_normal = has_normal && !normals.is_empty();
    Some(super::MeshData {
        path: Default::default(),
        positions: gather3(&positions),
        normals: if with_normal {
            gather3(&normals)
        } else {
            Vec::new()
        },
        uvs: if with_uv {
            used.par_iter()
                .map(|&v| DVec2::new(uvs[v as usize][0] as f64, uvs[v as usize][1] as f64))
                .collect()
        } else {
            Vec::new()
        },
        indices,
    })
}

/// The vertices the chunks' faces use, in the order of their first use (the corner that uses
/// a vertex first, in file order), and the triangles with vertices renumbered in that order:
/// what a serial walk numbering each vertex when it first meets it gives, done in parallel.
/// Every corner must be below `vertices`.
fn number_by_first_use(chunks: &[Chunk], vertices: usize) -> (Vec<u32>, Vec<[u32; 3]>) {
    // The position of each chunk's first corner among all corners.
    let starts: Vec<u64> = chunks
        .iter()
        .scan(0u64, |at, c| {
            let start = *at;
            *at += c.corners.len() as u64;
            Some(start)
        })
        .collect();
    // Each vertex's first corner: the least position naming it (order-independent).
    let first: Vec<AtomicU64> = (0..vertices)
        .into_par_iter()
        .map(|_| AtomicU64::new(u64::MAX))
        .collect();
    chunks.par_iter().zip(&starts).for_each(|(c, &start)| {
        for (at, &v) in (start..).zip(&c.corners) {
            let f = &first[v as usize];
            if f.load(Ordering::Relaxed) > at {
                f.fetch_min(at, Ordering::Relaxed);
            }
        }
    });
    // The used vertices in order: those whose first corner is where they stand.
    let used: Vec<Vec<u32>> = chunks
        .par_iter()
        .zip(&starts)
        .map(|(c, &start)| {
            (start..)
                .zip(&c.corners)
                .filter(|&(at, &v)| first[v as usize].load(Ordering::Relaxed) == at)
                .map(|(_, &v)| v)
                .collect()
        })
        .collect();
    let used = concat(used.iter().map(|u| &u[..]).collect());
    // `first` now holds each used vertex's number.
    used.par_iter()
        .enumerate()
        .for_each(|(k, &v)| first[v as usize].store(k as u64, Ordering::Relaxed));
    let number = |v: u32| first[v as usize].load(Ordering::Relaxed) as u32;
    let triangles: Vec<Vec<[u32; 3]>> = chunks
        .par_iter()
        .map(|c| {
            c.corners
                .chunks_exact(3)
                .map(|t| [number(t[0]), number(t[1]), number(t[2])])
                .collect()
        })
        .collect();
    (used, concat(triangles.iter().map(|t| &t[..]).collect()))
}

/// The parts one after another, copied in parallel.
fn concat<T: Copy + Default + Send + Sync>(parts: Vec<&[T]>) -> Vec<T> {
    let mut out = vec![T::default(); parts.iter().map(|p| p.len()).sum()];
    let mut rest = &mut out[..];
    let mut pieces = Vec::with_capacity(parts.len());
    for part in parts {
        let (piece, tail) = rest.split_at_mut(part.len());
        pieces.push((piece, part));
        rest = tail;
    }
    pieces
        .into_par_iter()
        .for_each(|(piece, part)| piece.copy_from_slice(part));
    out
}

/// `bytes` cut into parts of about `chunk_bytes`, each ending after a line end (or at the end).
fn split_at_lines(bytes: &[u8], chunk_bytes: usize) -> Vec<&[u8]> {
    let mut parts = Vec::with_capacity(bytes.len() / chunk_bytes.max(1) + 1);
    let mut rest = bytes;
    while !rest.is_empty() {
        let cut = match rest.get(chunk_bytes..) {
            None => rest.len(),
            Some(after) => after
                .iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |i| chunk_bytes + i + 1),
        };
        let (part, tail) = rest.split_at(cut);
        parts.push(part);
        rest = tail;
    }
    parts
}

/// The first `N` words as numbers (further words ignored, as `tobj` does).
fn numbers<'a, const N: usize>(words: &mut impl Iterator<Item = &'a str>) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    for o in &mut out {
        *o = words.next()?.parse().ok()?;
    }
    Some(out)
}

/// A face corner: its position index (0-based) and whether it names a texture coordinate
/// and a normal, both equal to the position index.
fn corner(word: &str) -> Option<(u32, bool, bool)> {
    let mut parts = word.split('/');
    let index = |s: &str| -> Option<u32> {
        let i: isize = s.parse().ok()?;
        u32::try_from(i.checked_sub(1)?).ok()
    };
    let v = index(parts.next()?)?;
    let mut named = [false; 2];
    for n in &mut named {
        match parts.next() {
            None | Some("") => {}
            Some(s) if index(s)? == v => *n = true,
            Some(_) => return None,
        }
    }
    parts.next().is_none().then_some((v, named[0], named[1]))
}

fn parse_chunk(text: &str) -> Option<Chunk> {
    let mut c = Chunk::default();
    let mut face = Vec::new();
    for line in text.split('\n') {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                c.positions.push(numbers::<3>(&mut words)?);
                if words.next().is_some() {
                    return None;
                }
            }
            Some("vt") => c.uvs.push(numbers::<2>(&mut words)?),
            Some("vn") => c.normals.push(numbers::<3>(&mut words)?),
            Some("f") => {
                face.clear();
                for w in words {
                    let (v, uv, n) = corner(w)?;
                    if c.form.is_some_and(|f| f != (uv, n)) {
                        return None;
                    }
                    c.form = Some((uv, n));
                    face.push(v);
                }
                if face.len() < 3 {
                    return None;
                }
                for k in 2..face.len() {
                    c.corners.extend([face[0], face[k - 1], face[k]]);
                }
            }
            Some("o" | "g") => {
                c.named = true;
                c.named_after_face |= !c.corners.is_empty();
            }
            Some("usemtl") if line.split_once(' ').unwrap_or_default().1.trim().is_empty() => {
                return None;
            }
            Some("l") => return None,
            _ => {}
        }
    }
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::scene::assets::read_with_tobj;

    fn pick<'a>(rng: &mut Rng, options: &[&'a str]) -> &'a str {
        options[rng.next_u32() as usize % options.len()]
    }

    fn number(rng: &mut Rng) -> String {
        let x = (rng.f32() - 0.5) * 10f32.powi(rng.next_u32() as i32 % 7 - 3);
        match rng.next_u32() % 4 {
            0 => format!("{x}"),
            1 => format!("{x:e}"),
            2 => format!("{x:.3}"),
            _ => format!("{}", (x * 10.0).round() as i32),
        }
    }

    /// A random OBJ file of the form the parallel reader takes: vertices, texture coordinates
    /// and normals (with and without a third texture value), faces of 3-6 corners of one form,
    /// comments, names before the faces, smoothing and material lines, blank lines, CRLF or
    /// LF, spaces or tabs, faces before or after the vertices they use, unused vertices.
    fn random_obj(rng: &mut Rng) -> String {
        let nv = 3 + rng.next_u32() as usize % 40;
        let form = pick(rng, &["v", "v/t", "v//n", "v/t/n"]);
        let sep = pick(rng, &[" ", "  ", "\t", " \t "]);
        let mut vertices = Vec::new();
        for _ in 0..nv {
            let p: Vec<String> = (0..3).map(|_| number(rng)).collect();
            vertices.push(format!("v{sep}{}", p.join(sep)));
            if form.contains('t') || rng.f32() < 0.2 {
                let w = if rng.f32() < 0.3 { " 0" } else { "" };
                vertices.push(format!("vt {} {}{w}", number(rng), number(rng)));
            }
            if form.contains('n') || rng.f32() < 0.2 {
                vertices.push(format!(
                    "vn {} {} {}",
                    number(rng),
                    number(rng),
                    number(rng)
                ));
            }
        }
        let mut faces = Vec::new();
        for _ in 0..1 + rng.next_u32() % 30 {
            let k = 3 + rng.next_u32() as usize % 4;
            let corners: Vec<String> = (0..k)
                .map(|_| {
                    // Corners use the first two thirds of the vertices more: some go unused.
                    let i = 1 + rng.next_u32() as usize % (nv * 2 / 3).max(3);
                    form.replace('v', &i.to_string())
                        .replace('t', &i.to_string())
                        .replace('n', &i.to_string())
                })
                .collect();
            faces.push(format!("f{sep}{}", corners.join(sep)));
            if rng.f32() < 0.1 {
                faces.push(
                    pick(
                        rng,
                        &["s 1", "s off", "usemtl red", "# a face", "", "vp 1 2"],
                    )
                    .into(),
                );
            }
        }
        let mut lines: Vec<String> = Vec::new();
        for _ in 0..rng.next_u32() % 3 {
            lines.push(
                pick(
                    rng,
                    &["# made by hand", "o thing", "g group", "mtllib a.mtl", ""],
                )
                .into(),
            );
        }
        if rng.f32() < 0.2 {
            lines.extend(faces);
            lines.extend(vertices);
        } else {
            lines.extend(vertices);
            lines.extend(faces);
        }
        let end = if rng.f32() < 0.3 { "\r\n" } else { "\n" };
        let mut text = lines.join(end);
        if rng.f32() < 0.5 {
            text.push_str(end);
        }
        text
    }

    /// On 400 random files, cut into chunks of a few bytes to many lines and read on 4 threads
    /// (chunks race to number shared vertices), the parallel reader gives exactly the mesh
    /// `tobj` reads: the same vertices in the same order, the same normals and texture
    /// coordinates (or none), the same triangles.
    #[test]
    fn reads_what_tobj_reads() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let mut rng = Rng::new(5);
        let (mut normals, mut uvs, mut polygons) = (0, 0, 0);
        for case in 0..400 {
            let text = random_obj(&mut rng);
            let path = std::path::Path::new("m.obj");
            let want = read_with_tobj(text.as_bytes(), path).unwrap();
            for chunk in [1, 23, 400, CHUNK_BYTES] {
                let got = pool.install(|| parse_in_chunks(text.as_bytes(), chunk));
                let got = got.map(|m| super::super::MeshData {
                    path: path.into(),
                    ..m
                });
                assert!(
                    got.as_ref() == Some(&want),
                    "case {case}, chunks of {chunk}:\n{text}"
                );
            }
            normals += usize::from(!want.normals.is_empty());
            uvs += usize::from(!want.uvs.is_empty());
            let faces = text.lines().filter(|l| l.starts_with("f")).count();
            polygons += usize::from(want.indices.len() > faces);
        }
        assert!(
            normals > 100 && uvs > 100 && polygons > 100,
            "{normals} {uvs} {polygons}"
        );
    }

    /// Files outside the form (and files with errors) are left to `tobj`.
    #[test]
    fn other_files_are_left_to_tobj() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n";
        assert!(parse(format!("{base}f 1 2 3\n").as_bytes()).is_some());
        for tail in [
            "f -3 -2 -1",
            "f 0 1 2",
            "f 1 2 5",
            "f 1 2",
            "f",
            "f 1 2 x",
            "f 1/2 2/2 3/3",
            "f 1/1 2/2 3",
            "f 1 2 3\nf 1/1 2/2 3/3",
            "f 1//4 2//2 3//3",
            "f 1/1/1/1 2 3",
            "f 1 2 3\ng second\nf 2 3 4",
            "f 1 2 3\no second",
            "v 1 2 3 1 0 0\nf 1 2 3",
            "v 1 2 3 2\nf 1 2 3",
            "v 1 2\nf 1 2 3",
            "vt 1\nf 1 2 3",
            "vn 1 x 0\nf 1 2 3",
            "l 1 2\nf 1 2 3",
            "usemtl\nf 1 2 3",
            "# no faces",
        ] {
            let text = format!("{base}{tail}\n");
            assert!(parse(text.as_bytes()).is_none(), "{tail}");
        }
        assert!(parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n# \xff\nf 1 2 3\n").is_none());
    }
}
