//! Forward-mode dual numbers with three partial derivatives, enough to
//! differentiate the colour difference (CIE Lab, CIEDE2000) by the three
//! components of a colour exactly, without writing its long derivative by hand.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A value and its derivatives by three inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dual {
    pub(crate) v: f64,
    pub(crate) d: [f64; 3],
}

impl Dual {
    pub(crate) fn constant(v: f64) -> Dual {
        Dual { v, d: [0.0; 3] }
    }

    /// The `i`-th input, of value `v`.
    pub(crate) fn input(v: f64, i: usize) -> Dual {
        let mut d = [0.0; 3];
        d[i] = 1.0;
        Dual { v, d }
    }

    /// f(self) given f's value and slope there.
    #[inline]
    fn chain(self, v: f64, slope: f64) -> Dual {
        Dual {
            v,
            d: self.d.map(|d| d * slope),
        }
    }

    /// √x; its derivative taken as 0 where x = 0 (where a distance is 0
    /// every direction increases it, and 0 is the subgradient).
    pub(crate) fn sqrt(self) -> Dual {
        let r = self.v.sqrt();
        self.chain(r, if r > 0.0 { 0.5 / r } else { 0.0 })
    }

    pub(crate) fn cbrt(self) -> Dual {
        let r = self.v.cbrt();
        self.chain(r, if r != 0.0 { 1.0 / (3.0 * r * r) } else { 0.0 })
    }

    pub(crate) fn powi(self, n: i32) -> Dual {
        self.chain(self.v.powi(n), n as f64 * self.v.powi(n - 1))
    }

    pub(crate) fn exp(self) -> Dual {
        let e = self.v.exp();
        self.chain(e, e)
    }

    pub(crate) fn sin_cos(self) -> (Dual, Dual) {
        let (s, c) = self.v.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }

    /// atan2(self, x); derivative 0 at the origin, where it has none.
    pub(crate) fn atan2(self, x: Dual) -> Dual {
        let (y, xv) = (self.v, x.v);
        let r2 = y * y + xv * xv;
        let v = y.atan2(xv);
        if r2 == 0.0 {
            return Dual::constant(v);
        }
        Dual {
            v,
            d: std::array::from_fn(|i| (xv * self.d[i] - y * x.d[i]) / r2),
        }
    }
}

impl Add for Dual {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        Dual {
            v: self.v + o.v,
            d: std::array::from_fn(|i| self.d[i] + o.d[i]),
        }
    }
}

impl Sub for Dual {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        Dual {
            v: self.v - o.v,
            d: std::array::from_fn(|i| self.d[i] - o.d[i]),
        }
    }
}

// The product rule: the derivative of a product is a sum.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Mul for Dual {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        Dual {
            v: self.v * o.v,
            d: std::array::from_fn(|i| self.d[i] * o.v + self.v * o.d[i]),
        }
    }
}

#[allow(clippy::suspicious_arithmetic_impl)]
impl Div for Dual {
    type Output = Dual;
    fn div(self, o: Dual) -> Dual {
        let inv = 1.0 / o.v;
        let v = self.v * inv;
        Dual {
            v,
            d: std::array::from_fn(|i| (self.d[i] - v * o.d[i]) * inv),
        }
    }
}

impl Neg for Dual {
    type Output = Dual;
    fn neg(self) -> Dual {
        Dual {
            v: -self.v,
            d: self.d.map(|d| -d),
        }
    }
}

impl Add<f64> for Dual {
    type Output = Dual;
    fn add(self, o: f64) -> Dual {
        Dual {
            v: self.v + o,
            ..self
        }
    }
}

impl Sub<f64> for Dual {
    type Output = Dual;
    fn sub(self, o: f64) -> Dual {
        Dual {
            v: self.v - o,
            ..self
        }
    }
}

impl Mul<f64> for Dual {
    type Output = Dual;
    fn mul(self, o: f64) -> Dual {
        Dual {
            v: self.v * o,
            d: self.d.map(|d| d * o),
        }
    }
}

impl Div<f64> for Dual {
    type Output = Dual;
    fn div(self, o: f64) -> Dual {
        self * (1.0 / o)
    }
}

impl Mul<Dual> for f64 {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        o * self
    }
}

impl Sub<Dual> for f64 {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        -o + self
    }
}

impl Add<Dual> for f64 {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        o + self
    }
}
