//! Field parsers shared by every entry: counts, numbers, rates, baud rates, names and
//! references, each failing with an error that names the field and the offending token.

use super::device_ref::DeviceRef;
use super::error::{ConfigError, ConfigErrorKind, Ctx};
use super::BAUD_RATES;
use crate::time::{checked_duration, period_of_rate, MAX_PERIOD};
use crate::wire::MAX_NAME_LEN;

/// Fails unless `args` has at least `min` tokens; `usage` names them.
pub fn need(ctx: &Ctx<'_>, args: &[&str], min: usize, usage: &str) -> Result<(), ConfigError> {
    if args.len() >= min {
        return Ok(());
    }
    let plural = if min == 1 { "" } else { "s" };
    Err(ctx.err(
        ConfigErrorKind::MissingArguments,
        format!(
            "expected {min} argument{plural} ({usage}), found {}",
            args.len()
        ),
    ))
}

/// A whole number in `lo..=hi`.
pub fn int_in(ctx: &Ctx<'_>, field: &str, tok: &str, lo: i64, hi: i64) -> Result<i64, ConfigError> {
    use std::num::IntErrorKind;
    let range = || {
        ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be between {lo} and {hi}, found {tok}"),
        )
    };
    match tok.parse::<i64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        Ok(_) => Err(range()),
        Err(e)
            if matches!(
                e.kind(),
                IntErrorKind::PosOverflow | IntErrorKind::NegOverflow
            ) =>
        {
            Err(range())
        }
        Err(_) => Err(ctx.err(
            ConfigErrorKind::BadNumber,
            format!("{field} must be a whole number, found '{tok}'"),
        )),
    }
}

/// A whole number in `lo..=hi`, as `u32` (callers pass non-negative bounds).
pub fn uint_in(
    ctx: &Ctx<'_>,
    field: &str,
    tok: &str,
    lo: u32,
    hi: u32,
) -> Result<u32, ConfigError> {
    let v = int_in(ctx, field, tok, i64::from(lo), i64::from(hi))?;
    u32::try_from(v).map_err(|_| {
        ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be between {lo} and {hi}, found {tok}"),
        )
    })
}

/// Any whole number that fits a C `int`.
pub fn any_int(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<i32, ConfigError> {
    let v = int_in(ctx, field, tok, i64::from(i32::MIN), i64::from(i32::MAX))?;
    Ok(i32::try_from(v).unwrap_or_default())
}

/// A finite number read as C++ reads `%f`/`%g`: the nearest `f32`.
pub fn f32_field(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    match tok.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be a finite number, found '{tok}'"),
        )),
        Err(_) => Err(ctx.err(
            ConfigErrorKind::BadNumber,
            format!("{field} must be a number, found '{tok}'"),
        )),
    }
}

/// A finite number read as C++ reads `%lf`.
pub fn f64_field(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f64, ConfigError> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be a finite number, found '{tok}'"),
        )),
        Err(_) => Err(ctx.err(
            ConfigErrorKind::BadNumber,
            format!("{field} must be a number, found '{tok}'"),
        )),
    }
}

/// A rate or period that must be greater than zero.
pub fn positive(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = f32_field(ctx, field, tok)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be greater than 0, found {tok}"),
        ))
    }
}

/// A rate that may be zero (the fly trackers then use a 1-second interval).
pub fn non_negative(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = f32_field(ctx, field, tok)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be 0 or more, found {tok}"),
        ))
    }
}

/// A report rate (per second) greater than 0 that a schedule can use: at least one report per
/// [`MAX_PERIOD`] (a smaller rate would panic in `Duration` arithmetic or never report).
pub fn rate(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = positive(ctx, field, tok)?;
    schedulable(ctx, field, tok, period_of_rate(f64::from(v)).is_some())?;
    Ok(v)
}

/// A report rate that may also be 0 (the fly trackers then use a 1-second interval).
pub fn rate_or_zero(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = non_negative(ctx, field, tok)?;
    schedulable(
        ctx,
        field,
        tok,
        v == 0.0 || period_of_rate(f64::from(v)).is_some(),
    )?;
    Ok(v)
}

/// A period in seconds, greater than 0 and at most [`MAX_PERIOD`].
pub fn period(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<f32, ConfigError> {
    let v = positive(ctx, field, tok)?;
    if checked_duration(f64::from(v)).is_none() {
        return Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!(
                "{field} must be at most {} seconds (about 31.7 years), found {tok}",
                MAX_PERIOD.as_secs()
            ),
        ));
    }
    Ok(v)
}

fn schedulable(ctx: &Ctx<'_>, field: &str, tok: &str, ok: bool) -> Result<(), ConfigError> {
    if ok {
        return Ok(());
    }
    Err(ctx.err(
        ConfigErrorKind::OutOfRange,
        format!(
            "{field} must be at least 1e-9 per second (one report every {} seconds, about 31.7 \
             years), found {tok}",
            MAX_PERIOD.as_secs()
        ),
    ))
}

/// A baud rate from [`BAUD_RATES`].
pub fn baud(ctx: &Ctx<'_>, tok: &str) -> Result<u32, ConfigError> {
    let v = int_in(ctx, "baud", tok, i64::from(i32::MIN), i64::from(i32::MAX))?;
    match BAUD_RATES.iter().find(|&&b| i64::from(b) == v) {
        Some(&b) => Ok(b),
        None => Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!(
                "baud must be one of 300, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, \
                 found {tok}"
            ),
        )),
    }
}

/// A device name this server will publish under.
pub fn device_name(ctx: &Ctx<'_>, field: &str, tok: &str) -> Result<String, ConfigError> {
    if tok.contains('@') {
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!(
                "{field} '{tok}' must not contain '@' (clients connect to NAME@host, so the \
                 name itself cannot have one)"
            ),
        ));
    }
    if tok.len() > MAX_NAME_LEN {
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!(
                "{field} '{tok}' is {} characters long; VRPN names are at most {MAX_NAME_LEN}",
                tok.len()
            ),
        ));
    }
    Ok(tok.to_owned())
}

/// A reference to another device; `NULL` gives `None` when `allow_null`.
pub fn device_ref(
    ctx: &Ctx<'_>,
    field: &str,
    tok: &str,
    allow_null: bool,
) -> Result<Option<DeviceRef>, ConfigError> {
    if tok == "NULL" {
        if allow_null {
            return Ok(None);
        }
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!("{field} cannot be NULL here; name a device as *NAME or NAME@host"),
        ));
    }
    DeviceRef::parse(tok)
        .map(Some)
        .map_err(|why| ctx.err(ConfigErrorKind::BadName, format!("{field} '{tok}' {why}")))
}

/// Fails unless a block line has at least `n` values after its keyword `line_kw`.
pub fn block_need(
    ctx: &Ctx<'_>,
    line_kw: &str,
    t: &[&str],
    n: usize,
    usage: &str,
) -> Result<(), ConfigError> {
    if t.len() >= n {
        return Ok(());
    }
    Err(ctx.err(
        ConfigErrorKind::BadBlockLine,
        format!(
            "{line_kw} line needs {n} values after '{line_kw}' ({usage}), found {}",
            t.len()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx() -> Ctx<'static> {
        Ctx::new("t.cfg", 7, "kw")
    }

    #[test]
    fn integers() {
        let c = ctx();
        assert_eq!(int_in(&c, "n", "+5", 0, 9), Ok(5));
        let e = int_in(&c, "n", "2.5", 0, 9).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.cfg:7: kw: n must be a whole number, found '2.5'"
        );
        let e = int_in(&c, "n", "10", 0, 9).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.cfg:7: kw: n must be between 0 and 9, found 10"
        );
        assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
        let e = int_in(&c, "n", "99999999999999999999", 0, 9).unwrap_err();
        assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
    }

    #[test]
    fn floats_are_f32_and_finite() {
        let c = ctx();
        assert_eq!(f32_field(&c, "r", "0.1"), Ok(0.1f32));
        assert_eq!(f32_field(&c, "r", ".5"), Ok(0.5));
        assert_eq!(f32_field(&c, "r", "1e2"), Ok(100.0));
        let e = f32_field(&c, "r", "60Hz").unwrap_err();
        assert_eq!(e.message(), "kw: r must be a number, found '60Hz'");
        let e = f32_field(&c, "r", "nan").unwrap_err();
        assert_eq!(e.message(), "kw: r must be a finite number, found 'nan'");
        let e = f32_field(&c, "r", "1e39").unwrap_err();
        assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
        let e = positive(&c, "rate", "0").unwrap_err();
        assert_eq!(e.message(), "kw: rate must be greater than 0, found 0");
        assert_eq!(non_negative(&c, "rate", "0"), Ok(0.0));
    }

    #[test]
    fn rates_and_periods_must_fit_a_schedule() {
        let c = ctx();
        assert_eq!(rate(&c, "rate", "60"), Ok(60.0));
        assert_eq!(rate(&c, "rate", "1e-9"), Ok(1e-9));
        for tiny in ["1e-20", "5e-20", "1e-10", "1e-45"] {
            let e = rate(&c, "rate", tiny).unwrap_err();
            assert_eq!(e.kind(), ConfigErrorKind::OutOfRange);
            assert_eq!(
                e.to_string(),
                format!(
                    "t.cfg:7: kw: rate must be at least 1e-9 per second (one report every \
                     1000000000 seconds, about 31.7 years), found {tiny}"
                )
            );
        }
        assert!(rate(&c, "rate", "0").is_err());
        assert_eq!(rate_or_zero(&c, "update_rate", "0"), Ok(0.0));
        assert!(rate_or_zero(&c, "update_rate", "1e-20").is_err());
        assert_eq!(period(&c, "period_seconds", "2.5"), Ok(2.5));
        let e = period(&c, "period_seconds", "1e30").unwrap_err();
        assert_eq!(
            e.message(),
            "kw: period_seconds must be at most 1000000000 seconds (about 31.7 years), found 1e30"
        );
        assert!(period(&c, "period_seconds", "0").is_err());
    }

    #[test]
    fn baud_rates() {
        let c = ctx();
        assert_eq!(baud(&c, "115200"), Ok(115200));
        let e = baud(&c, "9601").unwrap_err();
        assert!(e.message().ends_with("found 9601"), "{e}");
    }

    #[test]
    fn device_refs() {
        assert_eq!(DeviceRef::parse("*M0"), Ok(DeviceRef::Local("M0".into())));
        assert_eq!(
            DeviceRef::parse("M0@host:3884"),
            Ok(DeviceRef::Remote("M0@host:3884".into()))
        );
        assert!(DeviceRef::parse("*").is_err());
        assert!(DeviceRef::parse("@host").is_err());
        assert!(DeviceRef::parse("M0@").is_err());
        assert!(DeviceRef::parse("*M0@host").is_err());
        let e = DeviceRef::parse("M0").unwrap_err().to_string();
        assert!(e.contains("*M0") && e.contains("M0@host"), "{e}");
        assert_eq!(DeviceRef::Local("M0".into()).to_string(), "*M0");
        assert_eq!(DeviceRef::Local("M0".into()).name(), "M0");
        let c = ctx();
        assert_eq!(device_ref(&c, "d", "NULL", true), Ok(None));
        assert!(device_ref(&c, "d", "NULL", false).is_err());
    }

    #[test]
    fn names() {
        let c = ctx();
        assert!(device_name(&c, "name", "a@b").is_err());
        assert!(device_name(&c, "name", &"n".repeat(MAX_NAME_LEN)).is_ok());
        assert!(device_name(&c, "name", &"n".repeat(MAX_NAME_LEN + 1)).is_err());
    }
}
