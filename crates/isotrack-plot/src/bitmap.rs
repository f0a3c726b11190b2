//! A bitmap backend whose wide lines keep to their points (att49-1).
//!
//! plotters draws a line wider than one pixel as one polygon round the whole path, each
//! corner's two edges offset by half the width and met at their intersection. The outer side
//! of a sharp corner is capped at four half-widths, the inner side is not: at a near reversal
//! (a turn rate flipping between `+1e100` and `-1e100` from one sample to the next, drawn at
//! the panel's top and bottom) the inner edges meet far beyond the corner, and the polygon
//! reached over the neighbouring panels and off the image. [`SafeLines`] cuts a path at every
//! corner sharper than the one whose inner meeting point lies four half-widths away (the outer
//! side's own cap), so no part of a line lies further than two widths from its points; paths
//! without such a corner are drawn exactly as before.

use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};

/// `inner` with wide paths cut at their sharp corners (the module's documentation).
pub(crate) struct SafeLines<B: DrawingBackend>(pub(crate) B);

/// Cosine of the sharpest corner drawn joined: the offset edges of a corner of angle `a` meet
/// `d / sin(a / 2)` from it, `4 d` when `sin(a / 2) = 1/4`, so `cos a = 1 - 2 / 16`.
const SHARPEST_JOINED_COS: f64 = 0.875;

/// Whether the corner at `b` between `a -> b` and `b -> c` is sharper than plotters joins
/// within four half-widths.
fn too_sharp(a: BackendCoord, b: BackendCoord, c: BackendCoord) -> bool {
    let u = (f64::from(a.0 - b.0), f64::from(a.1 - b.1));
    let v = (f64::from(c.0 - b.0), f64::from(c.1 - b.1));
    let (lu, lv) = (u.0.hypot(u.1), v.0.hypot(v.1));
    lu > 0.0 && lv > 0.0 && (u.0 * v.0 + u.1 * v.1) / (lu * lv) > SHARPEST_JOINED_COS
}

/// `path` (repeated points dropped) cut at its too-sharp corners, each piece sharing its end
/// point with the next.
pub(crate) fn pieces(path: impl IntoIterator<Item = BackendCoord>) -> Vec<Vec<BackendCoord>> {
    let mut points: Vec<BackendCoord> = path.into_iter().collect();
    points.dedup();
    let mut out = vec![];
    let mut cur: Vec<BackendCoord> = vec![];
    for (i, &p) in points.iter().enumerate() {
        cur.push(p);
        if i > 0 && i + 1 < points.len() && too_sharp(points[i - 1], p, points[i + 1]) {
            out.push(std::mem::replace(&mut cur, vec![p]));
        }
    }
    out.push(cur);
    out
}

impl<B: DrawingBackend> DrawingBackend for SafeLines<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.draw_line(from, to, style)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        if style.stroke_width() <= 1 {
            return self.0.draw_path(path, style);
        }
        let points: Vec<BackendCoord> = path.into_iter().collect();
        let cut = pieces(points.iter().copied());
        if cut.len() == 1 {
            // No sharp corner: the path as given, drawn exactly as plotters draws it.
            return self.0.draw_path(points, style);
        }
        for piece in cut {
            self.0.draw_path(piece, style)?;
        }
        Ok(())
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.fill_polygon(vert, style)
    }
    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.draw_text(text, style, pos)
    }
    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<B::ErrorType>> {
        self.0.estimate_text_size(text, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.0.blit_bitmap(pos, size, src)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reversal_is_cut_a_gentle_corner_is_not() {
        // Up and straight back down one pixel to the right: a corner of about 1 degree.
        let p = pieces([(0, 0), (0, 100), (1, 0), (1, 100)]);
        assert_eq!(
            p,
            vec![
                vec![(0, 0), (0, 100)],
                vec![(0, 100), (1, 0)],
                vec![(1, 0), (1, 100)]
            ]
        );
        // A right angle (cos 0) and a 45-degree kink (cos -0.71) stay one path.
        assert_eq!(pieces([(0, 0), (10, 0), (10, 10), (20, 20)]).len(), 1);
        // 30 degrees is just within the cap (cos 0.866 < 0.875): joined; 20 degrees is cut.
        let deg = |a: f64| {
            (
                (100.0 * a.to_radians().cos()) as i32,
                (100.0 * a.to_radians().sin()) as i32,
            )
        };
        assert_eq!(pieces([deg(30.0), (0, 0), (100, 0)]).len(), 1);
        assert_eq!(pieces([deg(20.0), (0, 0), (100, 0)]).len(), 2);
        // Repeated points are no corner.
        assert_eq!(
            pieces([(0, 0), (5, 0), (5, 0), (10, 0)]),
            vec![vec![(0, 0), (5, 0), (10, 0)]]
        );
    }
}
