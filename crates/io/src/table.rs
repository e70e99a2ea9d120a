//! Plain-text tables for the terminal: each column as wide as its widest cell, two
//! spaces between columns, the first column left-aligned (the row names) and the
//! others right-aligned (numbers) unless made left-aligned (text); a table wider than a limit is cut into several
//! tables, each repeating the first column. Widths count characters, not bytes
//! (`§`, `²`).

/// Spaces between two columns.
pub const GAP: usize = 2;
/// The widest line navfuse prints in a table (a usual terminal).
pub const MAX_WIDTH: usize = 100;

/// A table of text cells with a header row.
#[derive(Clone, Debug, Default)]
pub struct TextTable {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
    /// Columns after the first that are left-aligned.
    left: Vec<usize>,
}

fn width(s: &str) -> usize {
    s.chars().count()
}

impl TextTable {
    /// A table with these column headers; the first is the row-name column.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        TextTable {
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
            left: Vec::new(),
        }
    }

    /// Left-align these columns (text) as well as the first.
    pub fn left_aligned(mut self, cols: &[usize]) -> Self {
        self.left.extend_from_slice(cols);
        self
    }

    /// Add a row; missing cells are empty, extra cells are an error of the caller
    /// (debug assertion) and are dropped.
    pub fn row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        let mut r: Vec<String> = cells.into_iter().map(Into::into).collect();
        debug_assert!(r.len() <= self.header.len(), "row wider than the header");
        r.resize(self.header.len(), String::new());
        self.rows.push(r);
    }

    /// Width of each column: its widest cell, header included.
    fn widths(&self) -> Vec<usize> {
        (0..self.header.len())
            .map(|c| {
                self.rows
                    .iter()
                    .map(|r| width(&r[c]))
                    .chain([width(&self.header[c])])
                    .max()
                    .unwrap_or(0)
            })
            .collect()
    }

    /// The table on one block of lines: header, a rule of dashes, the rows.
    pub fn render(&self) -> String {
        self.render_columns(&(0..self.header.len()).collect::<Vec<_>>())
    }

    /// The table cut into blocks of at most `max_width` characters a line (unless a
    /// single column is already wider), each block with the first column and as many
    /// of the following ones as fit; blocks separated by an empty line.
    pub fn render_wrapped(&self, max_width: usize) -> String {
        let w = self.widths();
        if w.is_empty() {
            return String::new();
        }
        let mut blocks: Vec<Vec<usize>> = Vec::new();
        let mut cur = vec![0];
        let mut cur_w = w[0];
        for (c, &cw) in w.iter().enumerate().skip(1) {
            if cur.len() > 1 && cur_w + GAP + cw > max_width {
                blocks.push(std::mem::replace(&mut cur, vec![0]));
                cur_w = w[0];
            }
            cur.push(c);
            cur_w += GAP + cw;
        }
        blocks.push(cur);
        blocks
            .iter()
            .map(|b| self.render_columns(b))
            .collect::<Vec<_>>()
            .join("\n")
    }

    fn render_columns(&self, cols: &[usize]) -> String {
        let w = self.widths();
        let line = |cells: &[String]| {
            let mut s = String::new();
            for (k, &c) in cols.iter().enumerate() {
                let pad = w[c] - width(&cells[c]);
                if k == 0 {
                    s.push_str(&cells[c]);
                    s.push_str(&" ".repeat(pad));
                } else if self.left.contains(&c) {
                    s.push_str(&" ".repeat(GAP));
                    s.push_str(&cells[c]);
                    s.push_str(&" ".repeat(pad));
                } else {
                    s.push_str(&" ".repeat(GAP + pad));
                    s.push_str(&cells[c]);
                }
            }
            s.truncate(s.trim_end().len());
            s.push('\n');
            s
        };
        let mut s = line(&self.header);
        let total: usize = cols.iter().map(|&c| w[c]).sum::<usize>() + GAP * (cols.len() - 1);
        s.push_str(&"-".repeat(total));
        s.push('\n');
        for r in &self.rows {
            s.push_str(&line(r));
        }
        s
    }
}

/// `text` as lines of at most `max_width` characters (words longer than that stay
/// whole), the first starting with `first`, the others with `rest`.
pub fn wrap_text(text: &str, max_width: usize, first: &str, rest: &str) -> String {
    let mut out = String::new();
    let mut line = first.to_string();
    let mut empty = true;
    for word in text.split_whitespace() {
        if !empty && width(&line) + 1 + width(word) > max_width {
            out.push_str(&line);
            out.push('\n');
            line = rest.to_string();
            empty = true;
        }
        if !empty {
            line.push(' ');
        }
        line.push_str(word);
        empty = false;
    }
    out.push_str(&line);
    out.push('\n');
    out
}

/// The longest line of `text` in characters.
pub fn max_line_width(text: &str) -> usize {
    text.lines().map(width).max().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wide_table() -> TextTable {
        let mut header = vec!["variant".to_string()];
        header.extend((0..12).map(|k| format!("metric {k} [m]")));
        let mut t = TextTable::new(header);
        for name in ["six_state_dead_reckoning", "ins"] {
            let mut r = vec![name.to_string()];
            // Values wider than the header, as seed 000's were.
            r.extend((0..12).map(|k| format!("{:.3} [{:.3}, {:.3}]", 1000.0 * k as f64, 1.0, 2.0)));
            t.row(r);
        }
        t
    }

    #[test]
    fn columns_fit_their_widest_cell_with_two_spaces_between() {
        let mut t = TextTable::new(["name", "a [m]", "b"]);
        t.row(["x", "123456.789", "1"]);
        t.row(["longer name", "1", "22"]);
        let s = t.render();
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines[0], format!("name{}a [m]   b", " ".repeat(14)));
        assert_eq!(lines[1], "-".repeat(27));
        assert_eq!(lines[2], format!("x{}123456.789   1", " ".repeat(12)));
        assert_eq!(lines[3], format!("longer name{}1  22", " ".repeat(11)));
        // Every cell starts after at least GAP spaces (right-aligned columns).
        for l in &lines[2..] {
            assert!(!l.contains("789 1"));
        }
    }

    #[test]
    fn wide_tables_wrap_within_the_limit_and_keep_columns_apart() {
        let t = wide_table();
        let one = t.render();
        assert!(max_line_width(&one) > 100);
        let s = t.render_wrapped(100);
        assert!(max_line_width(&s) <= 100, "{s}");
        // Each block repeats the row names, and every metric appears once.
        assert_eq!(
            s.matches("six_state_dead_reckoning").count(),
            s.split("\n\n").count()
        );
        for k in 0..12 {
            assert_eq!(s.matches(&format!("metric {k} [m]")).count(), 1);
        }
        // Separated: in every line, the cells are split by at least two spaces, so
        // splitting on two spaces gives back the cells.
        for block in s.split("\n\n") {
            let lines: Vec<&str> = block.lines().collect();
            let ncol = lines[0]
                .split("  ")
                .filter(|c| !c.trim().is_empty())
                .count();
            for l in lines.iter().skip(2) {
                let cells: Vec<&str> = l.split("  ").filter(|c| !c.trim().is_empty()).collect();
                assert_eq!(cells.len(), ncol, "line {l:?}");
            }
        }
    }

    #[test]
    fn left_aligned_columns_pad_on_the_right() {
        let mut t = TextTable::new(["n", "text", "v"]).left_aligned(&[1]);
        t.row(["a", "xy", "1"]);
        t.row(["b", "x", "10"]);
        let s = t.render();
        assert_eq!(s.lines().nth(2).unwrap(), "a  xy     1");
        assert_eq!(s.lines().nth(3).unwrap(), "b  x     10");
    }

    #[test]
    fn text_wraps_at_words() {
        let s = wrap_text("aaa bbb ccc ddd", 9, "  ", "    ");
        assert_eq!(s, "  aaa bbb\n    ccc\n    ddd\n");
    }

    #[test]
    fn non_ascii_cells_are_measured_in_characters() {
        let mut t = TextTable::new(["§", "m/s²"]);
        t.row(["é", "1"]);
        let s = t.render();
        assert_eq!(max_line_width(&s), 7);
        assert!(s.lines().nth(2).unwrap().ends_with("     1"));
    }
}
