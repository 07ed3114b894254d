//! Values the tasks' options share (counts, the paper's column sizes, positive numbers,
//! detector names), as clap value parsers whose errors name the value.

use dda_bench::PAPER_COLUMNS;

/// A count above zero.
pub fn positive_count(value: &str) -> Result<u64, String> {
    value
        .trim()
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("`{value}` is not a positive count"))
}

/// A count above zero, as a size.
pub fn positive_size(value: &str) -> Result<usize, String> {
    positive_count(value).map(|n| n as usize)
}

/// A finite number above zero.
pub fn positive_number(value: &str) -> Result<f64, String> {
    value
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && *x > 0.0)
        .ok_or_else(|| format!("`{value}` is not a positive number"))
}

/// The block count of one of the paper's columns (20, 93, 229, 826).
pub fn paper_column(value: &str) -> Result<usize, String> {
    value
        .trim()
        .parse()
        .ok()
        .filter(|m| PAPER_COLUMNS.iter().any(|c| c.blocks == *m))
        .ok_or_else(|| {
            format!("`{value}` is not the block count of a paper column (20, 93, 229, 826)")
        })
}

/// The name of a built-in detector.
pub fn detector(value: &str) -> Result<String, String> {
    dda_contact::detector_by_name(value.trim())
        .map(|_| value.trim().to_string())
        .map_err(|e| e.to_string())
}

/// A shard `I/N` of a job array: the I-th of N parts (1-based), as (I - 1, N).
pub fn shard(value: &str) -> Result<(usize, usize), String> {
    let bad = || format!("`{value}` is not a shard I/N with 1 <= I <= N");
    let (i, n) = value.trim().split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if i == 0 || i > n {
        return Err(bad());
    }
    Ok((i - 1, n))
}

#[cfg(test)]
mod tests {
    use super::{detector, paper_column, positive_count, positive_number, shard};

    /// A shard is I/N with 1 <= I <= N, returned 0-based.
    #[test]
    fn shards_are_read_and_checked() {
        assert_eq!(shard("1/1"), Ok((0, 1)));
        assert_eq!(shard(" 3 / 8 "), Ok((2, 8)));
        for bad in ["0/2", "3/2", "2", "a/b", "1/0", ""] {
            assert!(shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn errors_name_the_value() {
        assert_eq!(positive_count("2"), Ok(2));
        assert!(positive_count("0").is_err_and(|e| e.contains("`0`")));
        assert_eq!(paper_column("826"), Ok(826));
        assert!(paper_column("7").is_err_and(|e| e.contains("`7`")));
        assert!(positive_number("-1").is_err_and(|e| e.contains("`-1`")));
        assert!(detector("nope").is_err_and(|e| e.contains("nope")));
    }
}
