//! Bracketed scalar root finding (Brent's method), generic over the precision.

use crate::Real;

/// Finds `x` in `[a, b]` with `f(x) = 0`, given `f(a)` and `f(b)` of opposite sign.
///
/// Brent's method: inverse quadratic interpolation or secant steps when they stay inside the
/// bracket and shrink it fast enough, bisection otherwise. It cannot leave the bracket, so it
/// converges for any continuous `f`. Returns `None` if the bracket is invalid or if `max_iter`
/// is reached without meeting the tolerance `tol` on `x`.
pub fn brent<T: Real>(mut f: impl FnMut(T) -> T, a: T, b: T, fa: T, fb: T, tol: T, max_iter: usize) -> Option<T> {
    let two = T::of(2.0);
    let half = T::of(0.5);
    let (mut a, mut b, mut fa, mut fb) = (a, b, fa, fb);
    if fa == T::zero() {
        return Some(a);
    }
    if fb == T::zero() {
        return Some(b);
    }
    if (fa > T::zero()) == (fb > T::zero()) || !fa.is_finite() || !fb.is_finite() {
        return None;
    }
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..max_iter {
        if (fb > T::zero()) == (fc > T::zero()) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = two * T::epsilon() * b.abs() + half * tol;
        let xm = half * (c - b);
        if xm.abs() <= tol1 || fb == T::zero() {
            return Some(b);
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = two * xm * s;
                q = T::one() - s;
            } else {
                let qa = fa / fc;
                let r = fb / fc;
                p = s * (two * xm * qa * (qa - r) - (b - a) * (r - T::one()));
                q = (qa - T::one()) * (r - T::one()) * (s - T::one());
            }
            if p > T::zero() {
                q = -q;
            }
            p = p.abs();
            let min1 = T::of(3.0) * xm * q - (tol1 * q).abs();
            let min2 = (e * q).abs();
            if two * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        if d.abs() > tol1 {
            b += d;
        } else {
            b += if xm > T::zero() { tol1 } else { -tol1 };
        }
        fb = f(b);
        if !fb.is_finite() {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::brent;

    #[test]
    fn finds_roots_of_smooth_and_kinked_functions() {
        let r = brent(|x: f64| x * x - 2.0, 0.0, 2.0, -2.0, 2.0, 1e-14, 100).unwrap();
        assert!((r - 2f64.sqrt()).abs() < 1e-13);
        let g = |x: f64| if x < 0.3 { x - 0.3 } else { 100.0 * (x - 0.3) };
        let r = brent(g, -1.0, 1.0, g(-1.0), g(1.0), 1e-14, 200).unwrap();
        assert!((r - 0.3).abs() < 1e-12);
        let r32 = brent(|x: f32| x.exp() - 3.0, 0.0, 5.0, -2.0, 5f32.exp() - 3.0, 1e-6, 100).unwrap();
        assert!((r32 - 3f32.ln()).abs() < 1e-5);
    }

    #[test]
    fn rejects_a_bracket_without_sign_change() {
        assert!(brent(|x: f64| x * x + 1.0, -1.0, 1.0, 2.0, 2.0, 1e-12, 50).is_none());
    }
}
