//! Just enough JSON for JSON lines of flat objects (string, integer and boolean values),
//! the format xtask and `tools/*.py` exchange. Integers are exact up to `i128`.

use crate::Result;
use std::fmt::Write as _;

/// Builds one flat JSON object, keys in insertion order.
pub struct Obj {
    text: String,
}

impl Obj {
    /// An empty object.
    pub fn new() -> Self {
        Self {
            text: String::from("{"),
        }
    }

    fn key(&mut self, key: &str) {
        if self.text.len() > 1 {
            self.text.push(',');
        }
        push_str_literal(&mut self.text, key);
        self.text.push(':');
    }

    /// Adds an integer member.
    pub fn int(mut self, key: &str, value: impl Into<i128>) -> Self {
        self.key(key);
        let _ = write!(self.text, "{}", value.into());
        self
    }

    /// Adds a string member.
    pub fn str(mut self, key: &str, value: &str) -> Self {
        self.key(key);
        push_str_literal(&mut self.text, value);
        self
    }

    /// Adds a boolean member.
    pub fn bool(mut self, key: &str, value: bool) -> Self {
        self.key(key);
        self.text.push_str(if value { "true" } else { "false" });
        self
    }

    /// The object's text (one line).
    pub fn finish(mut self) -> String {
        self.text.push('}');
        self.text
    }
}

fn push_str_literal(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

/// A member value of a flat object.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Value {
    /// An integer.
    Int(i128),
    /// A string.
    Str(String),
    /// `true` or `false`.
    Bool(bool),
    /// `null`.
    Null,
}

/// A parsed flat object.
#[derive(Debug, Default)]
pub struct Flat(Vec<(String, Value)>);

impl Flat {
    /// The member `key`, if present.
    pub fn get(&self, key: &str) -> Option<&Value> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// The integer member `key`.
    pub fn int(&self, key: &str) -> Result<i128> {
        match self.get(key) {
            Some(Value::Int(v)) => Ok(*v),
            other => Err(format!(
                "member `{key}`: expected an integer, found {other:?}"
            )),
        }
    }

    /// The string member `key`.
    pub fn str(&self, key: &str) -> Result<&str> {
        match self.get(key) {
            Some(Value::Str(v)) => Ok(v),
            other => Err(format!(
                "member `{key}`: expected a string, found {other:?}"
            )),
        }
    }
}

/// Parses one line holding a flat JSON object (no nested objects or arrays, no floats).
pub fn parse_flat(line: &str) -> Result<Flat> {
    let mut p = Parser {
        s: line.as_bytes(),
        i: 0,
    };
    let mut members = Vec::new();
    p.ws();
    p.expect(b'{')?;
    p.ws();
    if p.peek() == Some(b'}') {
        p.i += 1;
    } else {
        loop {
            p.ws();
            let key = p.string()?;
            p.ws();
            p.expect(b':')?;
            p.ws();
            let value = p.value()?;
            members.push((key, value));
            p.ws();
            match p.next() {
                Some(b',') => continue,
                Some(b'}') => break,
                _ => return Err(p.error("`,` or `}`")),
            }
        }
    }
    p.ws();
    if p.i != p.s.len() {
        return Err(p.error("end of line"));
    }
    Ok(Flat(members))
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn next(&mut self) -> Option<u8> {
        let c = self.peek();
        self.i += 1;
        c
    }

    fn ws(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t' | b'\r' | b'\n')) {
            self.i += 1;
        }
    }

    fn error(&self, wanted: &str) -> String {
        format!("JSON: expected {wanted} at byte {}", self.i)
    }

    fn expect(&mut self, c: u8) -> Result {
        if self.next() == Some(c) {
            Ok(())
        } else {
            Err(self.error(&format!("`{}`", c as char)))
        }
    }

    fn string(&mut self) -> Result<String> {
        self.expect(b'"')?;
        let mut out = Vec::new();
        loop {
            match self.next() {
                None => return Err(self.error("closing `\"`")),
                Some(b'"') => break,
                Some(b'\\') => match self.next() {
                    Some(b'"') => out.push(b'"'),
                    Some(b'\\') => out.push(b'\\'),
                    Some(b'/') => out.push(b'/'),
                    Some(b'n') => out.push(b'\n'),
                    Some(b't') => out.push(b'\t'),
                    Some(b'r') => out.push(b'\r'),
                    Some(b'u') => {
                        let hex = self
                            .s
                            .get(self.i..self.i + 4)
                            .and_then(|h| std::str::from_utf8(h).ok())
                            .and_then(|h| u32::from_str_radix(h, 16).ok())
                            .and_then(char::from_u32)
                            .ok_or_else(|| self.error("four hex digits of a BMP character"))?;
                        self.i += 4;
                        let mut buf = [0u8; 4];
                        out.extend_from_slice(hex.encode_utf8(&mut buf).as_bytes());
                    }
                    _ => return Err(self.error("a known escape")),
                },
                Some(c) => out.push(c),
            }
        }
        String::from_utf8(out).map_err(|_| self.error("UTF-8"))
    }

    fn value(&mut self) -> Result<Value> {
        match self.peek() {
            Some(b'"') => self.string().map(Value::Str),
            Some(b't') => self.word("true", Value::Bool(true)),
            Some(b'f') => self.word("false", Value::Bool(false)),
            Some(b'n') => self.word("null", Value::Null),
            Some(b'-' | b'0'..=b'9') => {
                let start = self.i;
                self.i += 1;
                while matches!(self.peek(), Some(b'0'..=b'9')) {
                    self.i += 1;
                }
                let text = std::str::from_utf8(&self.s[start..self.i])
                    .map_err(|_| self.error("a number"))?;
                text.parse::<i128>()
                    .map(Value::Int)
                    .map_err(|e| format!("JSON: integer `{text}`: {e}"))
            }
            _ => Err(self.error("a value")),
        }
    }

    fn word(&mut self, word: &str, value: Value) -> Result<Value> {
        if self.s[self.i..].starts_with(word.as_bytes()) {
            self.i += word.len();
            Ok(value)
        } else {
            Err(self.error(word))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() -> Result {
        let line = Obj::new()
            .int("id", 7)
            .int("min", i128::from(i64::MIN))
            .int("max", u64::MAX)
            .str("s", "a\"b\\c\n")
            .bool("t", true)
            .finish();
        let flat = parse_flat(&line)?;
        assert_eq!(flat.int("id")?, 7);
        assert_eq!(flat.int("min")?, i128::from(i64::MIN));
        assert_eq!(flat.int("max")?, i128::from(u64::MAX));
        assert_eq!(flat.str("s")?, "a\"b\\c\n");
        assert_eq!(flat.get("t"), Some(&Value::Bool(true)));
        Ok(())
    }

    #[test]
    fn python_spacing_and_errors() -> Result {
        let flat = parse_flat(r#" { "id" : 3 , "cantools": "0a0b", "x": null } "#)?;
        assert_eq!(flat.int("id")?, 3);
        assert_eq!(flat.str("cantools")?, "0a0b");
        assert!(parse_flat(r#"{"id": 3"#).is_err());
        assert!(parse_flat(r#"{"id": 3} x"#).is_err());
        assert!(flat.int("cantools").is_err());
        Ok(())
    }
}
