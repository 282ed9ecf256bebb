//! Independent expectations: values a test computes on its own, in f64 and from the
//! scene rather than from the renderer's buffers, to hold a render against.

use gpurt::film::Film;

/// Mean of one column of the film's first channel.
pub fn column_mean(film: &Film, x: u32) -> f64 {
    (0..film.height)
        .map(|y| f64::from(film.get(x, y)[0]))
        .sum::<f64>()
        / f64::from(film.height)
}
