//! Mitsuba's `.spd` spectrum files: one `wavelength value` pair per line (nanometres, then the
//! value), `#` starting a comment, blank lines ignored.

use super::SampledSpectrum;

/// What is wrong with an `.spd` file's text; `line` is 1-based (0 for the whole file).
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("line {line}: {message}")]
pub struct SpdError {
    pub line: usize,
    pub message: String,
}

/// Reads the text of an `.spd` file.
pub fn parse_spd(text: &str) -> Result<SampledSpectrum, SpdError> {
    let (mut wavelengths, mut values) = (Vec::new(), Vec::new());
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let fields: Vec<&str> = line.split(|c: char| c.is_whitespace() || c == ',').filter(|f| !f.is_empty()).collect();
        if fields.is_empty() {
            continue;
        }
        let at = |message: String| SpdError { line: i + 1, message };
        let [w, v] = fields.as_slice() else {
            return Err(at(format!("expected `wavelength value`, found {} fields", fields.len())));
        };
        let number = |s: &str, what: &str| match s.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(at(format!("expected a {what}, found `{}`", s.escape_debug()))),
        };
        let w = number(w, "wavelength in nm")?;
        let v = number(v, "value")?;
        if let Some(&last) = wavelengths.last()
            && w <= last
        {
            return Err(at(format!("wavelengths must increase, but {w} follows {last}")));
        }
        wavelengths.push(w);
        values.push(v);
    }
    if wavelengths.len() < 2 {
        return Err(SpdError {
            line: 0,
            message: format!(
                "a spectrum file needs at least two `wavelength value` lines, found {}",
                wavelengths.len()
            ),
        });
    }
    SampledSpectrum::new(wavelengths, values).map_err(|message| SpdError { line: 0, message })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn reads_pairs_comments_and_blank_lines() {
        let s = parse_spd("# a comment\n\n400 0.5\n500\t0.25   # trailing\r\n600 1e-1\n").unwrap();
        assert_eq!(s.wavelengths(), &[400.0, 500.0, 600.0]);
        assert_eq!(s.values(), &[0.5, 0.25, 0.1]);
    }

    #[test]
    fn errors_name_the_line() {
        for (text, line, want) in [
            ("400 1\n500\n", 2, "found 1 fields"),
            ("400 1\n500 x\n", 2, "expected a value"),
            ("400 1\n300 2\n", 2, "must increase"),
            ("400 1 2\n", 1, "found 3 fields"),
            ("400 1\n", 0, "at least two"),
            ("", 0, "at least two"),
            ("400 1\n500 inf\n", 2, "expected a value"),
        ] {
            let e = parse_spd(text).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e}");
            assert!(e.message.contains(want), "{text:?}: {e}");
        }
    }

    proptest! {
        /// Any increasing list written out is read back exactly.
        #[test]
        fn written_spectra_read_back(start in 200.0f64..900.0, steps in prop::collection::vec((0.01f64..50.0, -1e3f64..1e3), 2..40)) {
            let mut w = start;
            let mut text = String::from("# generated\n");
            let (mut ws, mut vs) = (Vec::new(), Vec::new());
            for (dw, v) in steps {
                w += dw;
                text += &format!("{w:?} {v:?}\n");
                ws.push(w);
                vs.push(v);
            }
            let s = parse_spd(&text).unwrap();
            prop_assert_eq!(s.wavelengths(), ws.as_slice());
            prop_assert_eq!(s.values(), vs.as_slice());
        }

        /// Arbitrary bytes give a spectrum or an error, never a panic.
        #[test]
        fn arbitrary_text_never_panics(text in "(?s).{0,200}") {
            let _ = parse_spd(&text);
        }
    }
}
