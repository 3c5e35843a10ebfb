//! Where an OBJ file that `tobj` refused goes wrong: `tobj` names the kind of error but not the
//! line. [`first_bad_line`] walks the file with the checks `tobj` makes for that kind (numbers
//! that parse, the count of values on a `v` line, face corners of at most three parts, indices
//! that name an existing vertex) and returns the first line that fails them.

/// The first line (1-based number and its text) of `bytes` with the error `tobj` reported.
pub(super) fn first_bad_line(bytes: &[u8], error: &tobj::LoadError) -> Option<(usize, String)> {
    use tobj::LoadError as E;
    let lines = || bytes.split(|&b| b == b'\n').enumerate();
    if matches!(error, E::ReadError) {
        // Text that is not UTF-8.
        return lines()
            .find(|(_, l)| std::str::from_utf8(l).is_err())
            .map(|(i, l)| (i + 1, shown(&String::from_utf8_lossy(l))));
    }
    let text = std::str::from_utf8(bytes).ok()?;
    // `tobj` checks positive indices against every vertex read by the end of the group; all
    // the file's vertices are as far as it can reach.
    let count = |key: &str| {
        text.lines()
            .filter(|l| l.split_whitespace().next() == Some(key))
            .count() as i64
    };
    let total = [count("v"), count("vt"), count("vn")];
    let mut so_far = [0i64; 3];
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let bad = match words.next() {
            Some("v") => {
                so_far[0] += 1;
                let rest: Vec<&str> = words.collect();
                let coords = rest.len() >= 3 && rest[..3].iter().all(|w| w.parse::<f32>().is_ok());
                let w = (rest.len() == 4).then(|| rest[3].parse::<f32>());
                match error {
                    E::PositionParseError => !coords || w.as_ref().is_some_and(|w| w.is_err()),
                    E::ScalingByZeroError => coords && w.is_some_and(|w| w == Ok(0.0)),
                    E::ColorParseError => coords && (rest.len() == 5 || rest.len() > 6),
                    _ => false,
                }
            }
            Some(key @ ("vt" | "vn")) => {
                let (k, n, kind) = if key == "vt" {
                    (1, 2, E::TexcoordParseError)
                } else {
                    (2, 3, E::NormalParseError)
                };
                so_far[k] += 1;
                let numbers: Vec<&str> = words.take(n).collect();
                *error == kind
                    && !(numbers.len() == n && numbers.iter().all(|w| w.parse::<f32>().is_ok()))
            }
            Some("f" | "l") => words.any(|corner| corner_fails(corner, error, &so_far, &total)),
            _ => false,
        };
        if bad {
            return Some((i + 1, shown(line)));
        }
    }
    None
}

/// The first `v` line (1-based number and text) with a coordinate that is not a finite `f32`
/// (`nan`, `inf`, or beyond f32's range, as the mesh stores it).
pub(super) fn first_infinite_vertex(bytes: &[u8]) -> Option<(usize, String)> {
    let text = std::str::from_utf8(bytes).ok()?;
    text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        let infinite = words.next() == Some("v")
            && words
                .take(3)
                .any(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite()));
        infinite.then(|| (i + 1, shown(line)))
    })
}

/// Whether one face corner (`v`, `v/vt`, `v//vn`, `v/vt/vn`) has the error `error`.
fn corner_fails(
    corner: &str,
    error: &tobj::LoadError,
    so_far: &[i64; 3],
    total: &[i64; 3],
) -> bool {
    use tobj::LoadError as E;
    let parts: Vec<&str> = corner.split('/').collect();
    let parsed: Vec<Option<i64>> = parts
        .iter()
        .map(|p| if p.is_empty() { None } else { p.parse().ok() })
        .collect();
    let unparsed = parts
        .iter()
        .zip(&parsed)
        .any(|(p, v)| !p.is_empty() && v.is_none());
    if matches!(error, E::FaceParseError) {
        return parts.len() > 3 || unparsed;
    }
    let k = match error {
        E::FaceVertexOutOfBounds => 0,
        E::FaceTexCoordOutOfBounds => 1,
        E::FaceNormalOutOfBounds => 2,
        _ => return false,
    };
    // A relative index counts back from the vertices read so far; 0 names none.
    match parsed.get(k).copied().flatten() {
        Some(x) if x < 0 => so_far[k] + x < 0,
        Some(x) => x == 0 || x > total[k],
        None => false,
    }
}

/// A line as a diagnostic quotes it: trimmed, at most 60 characters.
fn shown(line: &str) -> String {
    let line = line.trim();
    match line.char_indices().nth(60) {
        Some((at, _)) => format!("{}...", &line[..at]),
        None => line.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::assets::read_with_tobj;

    /// Each kind of error `tobj` reports is found at its line, and the line is quoted.
    #[test]
    fn the_line_of_each_error_is_found() {
        let head = "# a mesh\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
        let cases = [
            ("v 0 0 x\n", "position parse error", 7),
            ("v 0 0\n", "position parse error", 7),
            ("v 0 0 0 0\n", "scaling (w) by zero", 7),
            ("v 0 0 0 1 1\n", "color parse error", 7),
            ("vt 0 z\n", "texcoord parse error", 7),
            ("vn 0 0\n", "normal parse error", 7),
            ("f 1 2 3\nf 1 2 x\n", "face parse error", 8),
            ("f 1/1/1/1 2 3\n", "face parse error", 7),
            ("f 1 2 3\nf 1 2 9\n", "face vertex index out of bounds", 8),
            ("f 1 2 3\nf -9 2 3\n", "face vertex index out of bounds", 8),
            ("f 0 2 3\n", "face vertex index out of bounds", 7),
            ("f 1/1 2/1 3/4\n", "face texcoord index out of bounds", 7),
            ("f 1//1 2//1 3//7\n", "face normal index out of bounds", 7),
        ];
        for (tail, kind, line) in cases {
            let text = format!("{head}{tail}");
            let e = read_with_tobj(text.as_bytes(), std::path::Path::new("m.obj")).unwrap_err();
            assert!(e.contains(kind), "{tail:?}: {e}");
            let want = format!("at line {line} (`{}`)", text.lines().nth(line - 1).unwrap());
            assert!(e.contains(&want), "{tail:?}: {e} (wanted {want})");
        }
        // A coordinate beyond f32's range.
        let text = format!("{head}v 0 1e39 0\nf 1 2 4\n");
        let e = crate::scene::assets::parse_obj(text.as_bytes(), std::path::Path::new("m.obj"))
            .unwrap_err();
        assert!(
            e.contains("`m.obj`, line 7 (`v 0 1e39 0`): a vertex coordinate"),
            "{e}"
        );
        // Not UTF-8.
        let mut bytes = head.as_bytes().to_vec();
        bytes.extend_from_slice(b"v 0 0 \xff\n");
        let e = read_with_tobj(&bytes, std::path::Path::new("m.obj")).unwrap_err();
        assert!(e.contains("at line 7"), "{e}");
    }
}
