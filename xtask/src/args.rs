//! Command-line pieces the tasks share: `--flag value` pairs, and the values that recur
//! (counts, the paper's column sizes), each error naming its flag.

use dda::bench::PAPER_COLUMNS;

/// The `(flag, value)` pairs of `args`, in order; an error names a flag without a value.
pub fn pairs(args: &[String]) -> Result<Vec<(&str, &str)>, String> {
    let mut out = Vec::with_capacity(args.len() / 2);
    let mut it = args.iter();
    while let Some(flag) = it.next() {
        let value = it.next().ok_or_else(|| format!("`{flag}` needs a value"))?;
        out.push((flag.as_str(), value.as_str()));
    }
    Ok(out)
}

/// `value` as a count above zero.
pub fn positive_count(flag: &str, value: &str) -> Result<u64, String> {
    value
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("{flag}: `{value}` is not a positive count"))
}

/// `value` as the block count of one of the paper's columns (20, 93, 229, 826).
pub fn paper_column(flag: &str, value: &str) -> Result<usize, String> {
    value
        .trim()
        .parse()
        .ok()
        .filter(|m| PAPER_COLUMNS.iter().any(|c| c.blocks == *m))
        .ok_or_else(|| {
            format!("{flag}: `{value}` is not the block count of a paper column (20, 93, 229, 826)")
        })
}

#[cfg(test)]
mod tests {
    use super::{pairs, paper_column, positive_count};

    #[test]
    fn errors_name_the_flag_and_the_value() {
        let args: Vec<String> = ["--runs", "3", "--out"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(pairs(&args[..2]), Ok(vec![("--runs", "3")]));
        assert_eq!(pairs(&args), Err("`--out` needs a value".into()));
        assert_eq!(positive_count("--jobs", "2"), Ok(2));
        assert!(positive_count("--jobs", "0").is_err_and(|e| e.contains("--jobs: `0`")));
        assert_eq!(paper_column("--model", "826"), Ok(826));
        assert!(paper_column("--model", "7").is_err_and(|e| e.contains("--model: `7`")));
    }
}
