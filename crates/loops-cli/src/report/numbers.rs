//! How numbers read on the page: thousands separators, percentages, durations, plurals.

/// `7560.0 s (2 h 06 min)`.
pub(crate) fn duration_text(seconds: f64) -> String {
    if !(seconds.is_finite() && seconds >= 60.0) {
        return format!("{seconds:.1} s");
    }
    let minutes = (seconds / 60.0).round() as u64;
    if minutes < 60 {
        format!("{seconds:.1} s ({minutes} min)")
    } else {
        format!("{seconds:.1} s ({} h {:02} min)", minutes / 60, minutes % 60)
    }
}

/// `1 pair`, `2 pairs`.
pub(crate) fn plural(count: usize, one: &str, many: &str) -> String {
    format!("{count} {}", if count == 1 { one } else { many })
}

/// `65,431,618`.
pub(crate) fn thousands(count: impl Into<u64>) -> String {
    let digits = count.into().to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `12.5 %` of `whole`, or `—` when `whole` is 0.
pub(crate) fn percent(part: usize, whole: usize) -> String {
    if whole == 0 { "—".to_owned() } else { format!("{:.1} %", 100.0 * part as f64 / whole as f64) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands_are_separated() {
        assert_eq!(thousands(0u64), "0");
        assert_eq!(thousands(999u64), "999");
        assert_eq!(thousands(1000u64), "1,000");
        assert_eq!(thousands(65_431_618u64), "65,431,618");
    }

    #[test]
    fn durations_plurals_and_percentages() {
        assert_eq!(duration_text(12.34), "12.3 s");
        assert_eq!(duration_text(600.0), "600.0 s (10 min)");
        assert_eq!(duration_text(7560.0), "7560.0 s (2 h 06 min)");
        assert_eq!(plural(1, "pair", "pairs"), "1 pair");
        assert_eq!(plural(2, "pair", "pairs"), "2 pairs");
        assert_eq!(percent(1, 8), "12.5 %");
        assert_eq!(percent(1, 0), "—");
    }
}
