//! JSON text by hand (numbers, strings, matrices) and the rotations and rigid
//! transforms the specs' JSON carries.

// ---------------------------------------------------------------------------------
// JSON text by hand

/// A JSON number token for `v`: the shortest exact decimal when finite; `NaN` and
/// `±1e999` (which no JSON parser accepts as a double) otherwise.
pub fn num(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v == f64::INFINITY {
        "1e999".into()
    } else if v == f64::NEG_INFINITY {
        "-1e999".into()
    } else {
        format!("{v:?}")
    }
}

pub(super) fn nums(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|&x| num(x)).collect();
    format!("[{}]", parts.join(", "))
}

pub(super) fn rows4(m: &[[f64; 4]; 4]) -> String {
    let r: Vec<String> = m.iter().map(|r| nums(r)).collect();
    format!("[{}]", r.join(", "))
}

pub(super) fn rows3(m: &[[f64; 3]; 3]) -> String {
    let r: Vec<String> = m.iter().map(|r| nums(r)).collect();
    format!("[{}]", r.join(", "))
}

/// A JSON string literal.
pub fn jstr(s: &str) -> String {
    let mut o = String::with_capacity(s.len() + 2);
    o.push('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// The rotation of a quaternion `[w, x, y, z]` (normalised; the identity when it is
/// near zero or not finite), row-major.
pub fn quat_rows(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(n > 1e-6 && n.is_finite()) {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let [w, x, y, z] = q.map(|v| v / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// A rigid 4×4, row-major, from a quaternion and a translation.
pub fn rigid(q: [f64; 4], t: [f64; 3]) -> [[f64; 4]; 4] {
    let r = quat_rows(q);
    [
        [r[0][0], r[0][1], r[0][2], t[0]],
        [r[1][0], r[1][1], r[1][2], t[1]],
        [r[2][0], r[2][1], r[2][2], t[2]],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The rotation of a quaternion as BOP's 9 row-major numbers.
pub fn rot9(q: [f64; 4]) -> [f64; 9] {
    let r = quat_rows(q);
    [
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    ]
}
