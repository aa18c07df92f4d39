//! A stack's indices at a list of wavelengths, laid out once for the lanes.

use num_complex::Complex64 as C64;

use super::arith::MAX_LANES;

/// A stack's indices at a list of wavelengths, laid out for the lanes: per
/// medium, n and n² at every wavelength in rows, and 2π/λ of every
/// wavelength, each row padded to a whole number of the widest vector by
/// repeating the last wavelength. Built once per
/// [`StackGrid`](crate::optics::StackGrid), it turns each lane group's
/// loads into one vector load per quantity, whatever the vector's width,
/// and takes n² and 2π/λ off the per-point work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spectrum {
    media: usize,
    wavelengths: usize,
    /// The rows' length: `wavelengths` rounded up to a multiple of [`MAX_LANES`].
    padded: usize,
    /// [medium][n.re, n.im, n².re, n².im][wavelength], rows of `padded`.
    rows: Vec<f64>,
    k0: Vec<f64>,
    wavelengths_nm: Vec<f64>,
    /// Every medium has the same index at every wavelength: the spectrum
    /// can take the non-dispersive kernel ([`constant`](super::constant)).
    non_dispersive: bool,
    /// Media that share their index at every wavelength with another.
    repeats: Repeats,
}

/// Distinct materials whose q the kernel keeps for their repeats.
pub(super) const SHARED_SLOTS: usize = 8;

/// Which media (below the ambient) have the same index as another medium at
/// every wavelength, so that one square root gives the q of all of them.
/// Up to [`SHARED_SLOTS`] such materials, among the first 256 media; the
/// others compute their own q.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Repeats {
    /// Per medium: 0 for none, else 1 + its material's slot.
    slot_of: Vec<u8>,
    /// (medium, slot) of each slot's first medium, which computes its q.
    pub(super) first: [(u8, u8); SHARED_SLOTS],
    pub(super) count: usize,
}

impl Default for Repeats {
    fn default() -> Self {
        Repeats::NONE
    }
}

impl Repeats {
    pub(super) const NONE: Repeats = Repeats {
        slot_of: Vec::new(),
        first: [(0, 0); SHARED_SLOTS],
        count: 0,
    };

    /// `indices` wavelength-major, `media` per wavelength.
    fn new(indices: &[C64], media: usize) -> Repeats {
        let mut r = Repeats::NONE;
        let rows = || indices.chunks_exact(media.max(1));
        // The first wavelength's indices rule most pairs out before any
        // other row is read.
        let first = indices.get(..media).unwrap_or(&[]);
        let same =
            |a: usize, b: usize| first.get(a) == first.get(b) && rows().all(|row| row[a] == row[b]);
        let media = media.min(256);
        r.slot_of = vec![0; media];
        for j in 1..media {
            if r.slot_of[j] != 0 || r.count == SHARED_SLOTS {
                continue;
            }
            let twins: Vec<usize> = (j + 1..media)
                .filter(|&k| r.slot_of[k] == 0 && same(j, k))
                .collect();
            if twins.is_empty() {
                continue;
            }
            let slot = r.count as u8;
            r.first[r.count] = (j as u8, slot);
            r.count += 1;
            for k in std::iter::once(j).chain(twins) {
                r.slot_of[k] = slot + 1;
            }
        }
        r
    }

    #[inline(always)]
    pub(super) fn slot(&self, j: usize) -> Option<usize> {
        match self.slot_of.get(j) {
            Some(&s) if s != 0 => Some(usize::from(s - 1)),
            _ => None,
        }
    }
}

impl Spectrum {
    /// `indices` wavelength-major, `media` per wavelength (as
    /// [`StackGrid`](crate::optics::StackGrid) stores them).
    pub fn new(indices: &[C64], media: usize, wavelengths_nm: &[f64]) -> Spectrum {
        assert_eq!(indices.len(), media * wavelengths_nm.len());
        let n = wavelengths_nm.len();
        let padded = n.div_ceil(MAX_LANES) * MAX_LANES;
        let at = |i: usize| i.min(n.saturating_sub(1));
        let mut rows = Vec::with_capacity(4 * media * padded);
        for j in 0..media {
            let index = |i: usize| indices[at(i) * media + j];
            rows.extend((0..padded).map(|i| index(i).re));
            rows.extend((0..padded).map(|i| index(i).im));
            rows.extend((0..padded).map(|i| (index(i) * index(i)).re));
            rows.extend((0..padded).map(|i| (index(i) * index(i)).im));
        }
        let wl: Vec<f64> = (0..padded).map(|i| wavelengths_nm[at(i)]).collect();
        let first = &indices[..media.min(indices.len())];
        let non_dispersive = indices.chunks_exact(media.max(1)).all(|row| row == first);
        Spectrum {
            non_dispersive,
            repeats: Repeats::new(indices, media),
            media,
            wavelengths: n,
            padded,
            rows,
            k0: wl.iter().map(|x| std::f64::consts::TAU / x).collect(),
            wavelengths_nm: wl,
        }
    }

    /// Media per wavelength (N + 2).
    pub(super) fn media(&self) -> usize {
        self.media
    }

    /// How many wavelengths (without the padding).
    pub(super) fn wavelengths(&self) -> usize {
        self.wavelengths
    }

    /// Every medium has the same index at every wavelength.
    pub fn is_non_dispersive(&self) -> bool {
        self.non_dispersive
    }

    pub(super) fn repeats(&self) -> &Repeats {
        &self.repeats
    }

    /// 2π/λ at every wavelength, padded.
    pub(super) fn k0(&self) -> &[f64] {
        &self.k0
    }

    /// The wavelengths in nm, padded.
    pub(super) fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// Medium j's n.re, n.im, n².re or n².im (`quantity` 0 to 3) at every
    /// wavelength, padded.
    #[inline(always)]
    pub(super) fn medium_row(&self, j: usize, quantity: usize) -> &[f64] {
        let start = (4 * j + quantity) * self.padded;
        &self.rows[start..start + self.padded]
    }
}
