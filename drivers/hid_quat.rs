//! The few quaternion operations the C++ HID trackers use (UNC quatlib's), in quatlib's
//! element order `[x, y, z, w]` and its exact arithmetic, so the values match bit for bit.

/// `[x, y, z, w]`.
pub type Quat = [f64; 4];
/// `[x, y, z]`.
pub type Vec3 = [f64; 3];

const X: usize = 0;
const Y: usize = 1;
const Z: usize = 2;
const W: usize = 3;

/// quatlib's `Q_EPSILON`.
const EPSILON: f64 = 1e-10;

/// `q_mult`: the product `l * r`.
pub fn mult(l: &Quat, r: &Quat) -> Quat {
    let mut d = [0.0; 4];
    d[W] = l[W] * r[W] - l[X] * r[X] - l[Y] * r[Y] - l[Z] * r[Z];
    d[X] = l[W] * r[X] + l[X] * r[W] + l[Y] * r[Z] - l[Z] * r[Y];
    d[Y] = l[W] * r[Y] + l[Y] * r[W] + l[Z] * r[X] - l[X] * r[Z];
    d[Z] = l[W] * r[Z] + l[Z] * r[W] + l[X] * r[Y] - l[Y] * r[X];
    d
}

/// `q_normalize`.
pub fn normalize(q: &Quat) -> Quat {
    let f = 1.0 / (q[X] * q[X] + q[Y] * q[Y] + q[Z] * q[Z] + q[W] * q[W]).sqrt();
    [q[X] * f, q[Y] * f, q[Z] * f, q[W] * f]
}

/// `q_invert`: the conjugate over the squared norm.
pub fn invert(q: &Quat) -> Quat {
    let n = 1.0 / (q[X] * q[X] + q[Y] * q[Y] + q[Z] * q[Z] + q[W] * q[W]);
    [-q[X] * n, -q[Y] * n, -q[Z] * n, q[W] * n]
}

/// `q_exp` of a quaternion whose scalar part is taken as zero.
pub fn exp(q: &Quat) -> Quat {
    let theta = (q[X] * q[X] + q[Y] * q[Y] + q[Z] * q[Z]).sqrt();
    let scale = if theta > EPSILON {
        theta.sin() / theta
    } else {
        1.0
    };
    [scale * q[X], scale * q[Y], scale * q[Z], theta.cos()]
}

/// `q_vec_magnitude`.
pub fn magnitude(v: &Vec3) -> f64 {
    (v[X] * v[X] + v[Y] * v[Y] + v[Z] * v[Z]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quatlib_identities() {
        let q = normalize(&[1.0, 2.0, 3.0, 4.0]);
        let i = mult(&q, &invert(&q));
        assert!((i[W] - 1.0).abs() < 1e-15 && i[X].abs() < 1e-15);
        assert_eq!(exp(&[0.0, 0.0, 0.0, 7.0]), [0.0, 0.0, 0.0, 1.0]);
        let e = exp(&[std::f64::consts::FRAC_PI_4, 0.0, 0.0, 0.0]);
        assert!((e[X] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
        assert_eq!(magnitude(&[3.0, 4.0, 12.0]), 13.0);
        // i·j = k
        assert_eq!(
            mult(&[1.0, 0.0, 0.0, 0.0], &[0.0, 1.0, 0.0, 0.0]),
            [0.0, 0.0, 1.0, 0.0]
        );
    }
}
