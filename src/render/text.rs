//! The built-in 3 × 5 pixel font ([`draw_text`], [`text_size`]): digits, `A`-`Z` and a few
//! signs, no system font library.

use super::*;

pub(super) const FONT_CHARS: &str = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ.-:=/()+,%|_'*<>[]";
/// 3 × 5 glyphs, one octal digit per row (top row first, left column the high bit).
pub(super) const FONT_BITS: [u16; 54] = [
    0o75557, 0o26227, 0o71747, 0o71717, 0o55711, 0o74717, 0o74757, 0o71122, 0o75757, 0o75717,
    0o25755, 0o65656, 0o34443, 0o65556, 0o74647, 0o74644, 0o34553, 0o55755, 0o72227, 0o11152,
    0o55655, 0o44447, 0o57755, 0o65555, 0o25552, 0o65644, 0o25563, 0o65655, 0o34216, 0o72222,
    0o55557, 0o55552, 0o55775, 0o55255, 0o55222, 0o71247, 0o00002, 0o00700, 0o02020, 0o07070,
    0o11244, 0o24442, 0o21112, 0o02720, 0o00024, 0o51245, 0o22222, 0o00007, 0o22000, 0o05250,
    0o12421, 0o42124, 0o64446, 0o31113,
];

/// Writes `s` on `pixmap` with the built-in 3 × 5 pixel font, its top left corner at `(x, y)`,
/// each font pixel `scale` pixels wide (a character advances 4 font pixels, a line 6). Lower
/// case is drawn as upper case; characters the font lacks (see the [module docs](crate::render)) leave
/// a blank; `\n` starts a new line.
///
/// ```
/// use rapier_touch::render::{draw_text, text_size, Color, Pixmap};
/// let mut pm = Pixmap::new(120, 40).unwrap();
/// draw_text(&mut pm, 4.0, 4.0, 2.0, "F = 0.25 N", Color::BLACK);
/// assert_eq!(text_size("F = 0.25 N", 2.0), (78.0, 10.0));
/// ```
pub fn draw_text(pixmap: &mut Pixmap, x: f32, y: f32, scale: f32, s: &str, color: Color) {
    text(pixmap, x, y, scale, s, color);
}

/// Width and height in pixels of `s` as [`draw_text`] writes it at `scale` (the longest
/// line; trailing spacing excluded).
pub fn text_size(s: &str, scale: f32) -> (f32, f32) {
    let lines = s.lines().count().max(1);
    let chars = s.lines().map(|l| l.chars().count()).max().unwrap_or(0);
    let w = (4 * chars).saturating_sub(1) as f32 * scale;
    (w, (6 * lines - 1) as f32 * scale)
}

/// Writes `s` with its top left corner at `(x, y)`, each font pixel `scale` pixels wide.
pub(super) fn text(pm: &mut Pixmap, x: f32, y: f32, scale: f32, s: &str, c: Color) {
    let p = paint(c);
    for (line, s) in s.lines().enumerate() {
        for (k, ch) in s.chars().enumerate() {
            let Some(i) = FONT_CHARS.find(ch.to_ascii_uppercase()) else {
                continue;
            };
            for bit in (0..15).filter(|b| FONT_BITS[i] >> (14 - b) & 1 == 1) {
                let px = x + (4 * k + bit % 3) as f32 * scale;
                let py = y + (6 * line + bit / 3) as f32 * scale;
                if let Some(r) = Rect::from_xywh(px, py, scale, scale) {
                    pm.fill_rect(r, &p, Transform::identity(), None);
                }
            }
        }
    }
}
