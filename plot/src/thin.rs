//! Thinning: a series of many thousand points is cut to what the picture can show.
//!
//! A time series (x never decreasing) keeps, per pixel column, its first, lowest, highest and
//! last point, so spikes stay visible and the line's shape is exact at the picture's
//! resolution. Any other series (a path) keeps a point only once it is half a pixel away
//! from the last one kept.

/// Axis ranges and the plotting area's size in pixels.
#[derive(Clone, Copy, Debug)]
pub struct Grid {
    /// x range.
    pub x: (f64, f64),
    /// y range.
    pub y: (f64, f64),
    /// Plotting area (pixels).
    pub pixels: (u32, u32),
}

impl Grid {
    fn pixels_of(self, (x, y): (f64, f64)) -> (f64, f64) {
        let scale = |v: f64, (lo, hi): (f64, f64), px: u32| {
            if hi > lo {
                (v - lo) / (hi - lo) * f64::from(px)
            } else {
                0.0
            }
        };
        (
            scale(x, self.x, self.pixels.0),
            scale(y, self.y, self.pixels.1),
        )
    }
}

/// The points of one unbroken line (all finite), thinned for `grid`.
pub fn thin(points: &[(f64, f64)], grid: &Grid) -> Vec<(f64, f64)> {
    if points.windows(2).all(|w| match w {
        [a, b] => a.0 <= b.0,
        _ => true,
    }) {
        thin_columns(points, grid)
    } else {
        thin_distance(points, grid)
    }
}

fn thin_columns(points: &[(f64, f64)], grid: &Grid) -> Vec<(f64, f64)> {
    let mut kept = Vec::new();
    let mut column: Vec<(f64, f64)> = Vec::new();
    let mut current = None;
    for &p in points {
        let c = grid.pixels_of(p).0.floor();
        if current != Some(c) {
            flush(&mut column, &mut kept);
            current = Some(c);
        }
        column.push(p);
    }
    flush(&mut column, &mut kept);
    kept
}

/// Moves the first, lowest, highest and last point of `column` (in their order) to `kept`.
fn flush(column: &mut Vec<(f64, f64)>, kept: &mut Vec<(f64, f64)>) {
    let by_y = |a: &(usize, &(f64, f64)), b: &(usize, &(f64, f64))| a.1.1.total_cmp(&b.1.1);
    let low = column.iter().enumerate().min_by(by_y).map(|(i, _)| i);
    let high = column.iter().enumerate().max_by(by_y).map(|(i, _)| i);
    let last = column.len().checked_sub(1);
    for (i, p) in column.iter().enumerate() {
        if i == 0 || Some(i) == low || Some(i) == high || Some(i) == last {
            kept.push(*p);
        }
    }
    column.clear();
}

fn thin_distance(points: &[(f64, f64)], grid: &Grid) -> Vec<(f64, f64)> {
    let mut kept: Vec<(f64, f64)> = Vec::new();
    let mut last_px: Option<(f64, f64)> = None;
    for &p in points {
        let px = grid.pixels_of(p);
        if last_px.is_none_or(|l| (px.0 - l.0).abs() >= 0.5 || (px.1 - l.1).abs() >= 0.5) {
            kept.push(p);
            last_px = Some(px);
        }
    }
    if let (Some(end), Some(k)) = (points.last(), kept.last())
        && end != k
    {
        kept.push(*end);
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRID: Grid = Grid {
        x: (0.0, 10.0),
        y: (-1.0, 1.0),
        pixels: (100, 50),
    };

    #[test]
    fn a_time_series_keeps_at_most_four_points_per_column_and_its_spikes() {
        // 10 000 points over 100 pixel columns, one spike.
        let mut points: Vec<(f64, f64)> = (0..10_000)
            .map(|k| (k as f64 * 1e-3, (k as f64 * 1e-3).sin() * 0.5))
            .collect();
        points[5_003].1 = 0.99;
        let kept = thin(&points, &GRID);
        assert!(kept.len() <= 4 * 101, "{}", kept.len());
        assert!(kept.contains(&points[5_003]));
        assert_eq!(kept.first(), points.first());
        assert_eq!(kept.last(), points.last());
        assert!(kept.windows(2).all(|w| w[0].0 <= w[1].0), "order kept");
    }

    #[test]
    fn a_path_keeps_points_half_a_pixel_apart_and_its_end() {
        // A circle of radius 1 (10 by 25 px) drawn with 100 000 points.
        let points: Vec<(f64, f64)> = (0..=100_000)
            .map(|k| {
                let a = k as f64 * 2.0 * std::f64::consts::PI / 100_000.0;
                (5.0 + a.cos(), a.sin() * 0.9)
            })
            .collect();
        let kept = thin(&points, &GRID);
        assert!(kept.len() < 300, "{}", kept.len());
        assert!(kept.len() > 50, "{}", kept.len());
        assert_eq!(kept.last(), points.last());
    }
}
