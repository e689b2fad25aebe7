//! The cell-case machinery of marching cubes: the cube's edges and faces, the face-by-face
//! linking of a cell's crossings into loops (asymptotic decider on ambiguous faces), safe fans,
//! and the table of the 256 sign cases built once from the same linking.

// Index loops over corners, faces and edges follow the formulas.
#![allow(clippy::needless_range_loop)]

/// Edges as (lower corner, axis); the upper corner is lower + axis bit.
// corner c has offset (c & 1, c >> 1 & 1, c >> 2 & 1)
pub(super) const EDGES: [(u8, u8); 12] = [
    (0, 0),
    (2, 0),
    (4, 0),
    (6, 0),
    (0, 1),
    (1, 1),
    (4, 1),
    (5, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (3, 2),
];

/// Faces as corners in counter-clockwise order seen from outside the cell.
const FACES: [[u8; 4]; 6] = [
    [0, 4, 6, 2],
    [1, 3, 7, 5],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 2, 3, 1],
    [4, 5, 7, 6],
];

const fn edge_of(a: u8, b: u8) -> u8 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    let axis = match hi ^ lo {
        1 => 0,
        2 => 1,
        _ => 2,
    };
    let mut e = 0;
    while e < 12 {
        if EDGES[e].0 == lo && EDGES[e].1 == axis {
            return e as u8;
        }
        e += 1;
    }
    255
}

/// For each face, the cell edge between corner i and corner i+1.
const FACE_EDGES: [[u8; 4]; 6] = {
    let mut t = [[0u8; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let mut i = 0;
        while i < 4 {
            t[f][i] = edge_of(FACES[f][i], FACES[f][(i + 1) % 4]);
            i += 1;
        }
        f += 1;
    }
    t
};

/// For each cell edge, the bit set of cell edges lying on a common cube face with it.
const SHARE: [u16; 12] = {
    let mut t = [0u16; 12];
    let mut f = 0;
    while f < 6 {
        let mut a = 0;
        while a < 4 {
            let mut b = 0;
            while b < 4 {
                t[FACE_EDGES[f][a] as usize] |= 1 << FACE_EDGES[f][b];
                b += 1;
            }
            a += 1;
        }
        f += 1;
    }
    t
};

/// Where a cell's triangles come from: a precomputed list for a case without ambiguous faces
/// (the linking then depends on the signs alone), or the general path.
#[derive(Clone, Copy)]
pub(super) struct CaseEntry {
    /// Triangles as triples of cell edges.
    pub(super) tris: [[u8; 3]; 10],
    pub(super) count: u8,
    /// Ambiguous face or a loop that needs a centre vertex: link this cell from its values.
    pub(super) general: bool,
}

/// The 256 cases, built once from the same face-by-face linking as the general path.
pub(super) fn case_table() -> &'static [CaseEntry; 256] {
    static TABLE: std::sync::OnceLock<[CaseEntry; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [CaseEntry {
            tris: [[0; 3]; 10],
            count: 0,
            general: false,
        }; 256];
        for case in 1..255usize {
            let e = &mut t[case];
            let (next, ambiguous) = link(case as u8, None);
            if ambiguous {
                e.general = true;
                continue;
            }
            let mut n = 0;
            let ok = for_each_loop(&next, |lp| match safe_fan(lp) {
                Some(s) => {
                    let m = lp.len();
                    for o in 1..m - 1 {
                        e.tris[n] = [lp[s], lp[(s + o) % m], lp[(s + o + 1) % m]];
                        n += 1;
                    }
                    true
                }
                None => false,
            });
            e.count = n as u8;
            e.general = !ok;
        }
        t
    })
}

/// Link a cell's crossings face by face (`next[e]` = the crossing after `e` in its loop, 255
/// for edges without a crossing). Ambiguous faces use the asymptotic decider on `val`
/// (corner values minus level); with `val = None` the second result reports that the case
/// has an ambiguous face (and `next` is incomplete).
pub(super) fn link(case: u8, val: Option<&[f64; 8]>) -> ([u8; 12], bool) {
    let inside = |c: u8| case >> c & 1 == 1;
    let mut next = [255u8; 12];
    let mut ambiguous = false;
    for f in 0..6 {
        let q = FACES[f];
        let ins = [inside(q[0]), inside(q[1]), inside(q[2]), inside(q[3])];
        let fe = FACE_EDGES[f];
        let mut enter = [0usize; 2];
        let mut leave = [0usize; 2];
        let (mut ne, mut nl) = (0, 0);
        for i in 0..4 {
            let (a, bb) = (ins[i], ins[(i + 1) % 4]);
            if !a && bb {
                enter[ne] = i;
                ne += 1;
            } else if a && !bb {
                leave[nl] = i;
                nl += 1;
            }
        }
        if ne == 1 {
            next[fe[enter[0]] as usize] = fe[leave[0]];
        } else if ne == 2 {
            ambiguous = true;
            let Some(val) = val else { continue };
            // asymptotic decider: inside corners joined iff their product exceeds the other pair's
            let (p_in, p_out) = if ins[0] {
                (
                    val[q[0] as usize] * val[q[2] as usize],
                    val[q[1] as usize] * val[q[3] as usize],
                )
            } else {
                (
                    val[q[1] as usize] * val[q[3] as usize],
                    val[q[0] as usize] * val[q[2] as usize],
                )
            };
            let joined = p_in > p_out;
            for &e in &enter {
                // separated: pair with the next edge (around one inside corner);
                // joined: with the previous edge (around one outside corner)
                let partner = if joined { (e + 3) % 4 } else { (e + 1) % 4 };
                next[fe[e] as usize] = fe[partner];
            }
        }
    }
    (next, ambiguous)
}

/// Call `f` on every loop of `next` (in order of its smallest edge); stops and returns false
/// as soon as `f` does.
pub(super) fn for_each_loop(next: &[u8; 12], mut f: impl FnMut(&[u8]) -> bool) -> bool {
    let mut seen = 0u16;
    for start in 0..12u8 {
        if next[start as usize] == 255 || seen >> start & 1 == 1 {
            continue;
        }
        let mut lp = [0u8; 12];
        let mut n = 0;
        let mut cur = start;
        loop {
            seen |= 1 << cur;
            lp[n] = cur;
            n += 1;
            cur = next[cur as usize];
            if cur == start || n == 12 {
                break;
            }
        }
        if !f(&lp[..n]) {
            return false;
        }
    }
    true
}

/// A fan from `lp[s]` is safe when none of its diagonals joins two vertices of one cube face
/// (a neighbour could draw the same diagonal: non-manifold edge).
pub(super) fn safe_fan(lp: &[u8]) -> Option<usize> {
    let n = lp.len();
    (0..n).find(|&s| (2..n - 1).all(|o| SHARE[lp[s] as usize] >> lp[(s + o) % n] & 1 == 0))
}
