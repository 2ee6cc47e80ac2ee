//! `cargo xtask docs` (the check command's `docs` stage) and `cargo xtask book`: the
//! documentation is a front page (README.md) and a book (mdBook, `docs/`), and neither may
//! drift from the code. In order, the stage
//!
//! 1. builds the book (`mdbook build docs`, into `target/book`, beside the API docs in
//!    `target/doc`, so that the crates' links into the book resolve);
//! 2. builds the API docs with warnings denied (`cargo doc --workspace --no-deps
//!    --keep-going`, `RUSTDOCFLAGS="-D warnings"`), so a broken intra-doc link fails (every
//!    crate's at once); the steps after it run even when it fails;
//! 3. checks every relative link (see [`check_links`]): of the Markdown sources as they read
//!    on the repository's web view (README.md and `docs/src/**/*.md`: files and heading
//!    anchors), of the built book's pages (files and `id`s), and of the crate pages that
//!    leave the API docs for the book (`../../book/os.html#the-kernel`);
//! 4. runs the examples: every fenced block of README.md and `docs/src/**/*.md` whose info
//!    string is `console` is a transcript (see [`transcripts`]), and each of its commands
//!    must print what the block shows (see [`output_matches`]), so an example cannot drift.
//!    Each command runs in a bash of its own (see [`run_examples`]): files written by one
//!    are there for the next, but not its `cd` or variables.
//!
//! `cargo xtask docs --file PATH` runs the examples of some files only, and `--no-examples`
//! none (a quick check while writing; the check command never passes either): the book,
//! the API docs and every link are still checked. `cargo xtask book [--open]` builds the
//! book and checks its links only, installing mdBook first if it is missing.
//!
//! The Markdown is read by a small scanner, not a full CommonMark parser: fenced code blocks
//! (indented or not), code spans and HTML comments are skipped; inline links and images,
//! link reference definitions and the `href`/`src` of `<a>`/`<img>` tags are checked;
//! indented code blocks, fences inside block quotes and autolinks (always absolute) are not
//! looked at.

use crate::process::{root, target_dir, Cmd};
use crate::Result;
use std::collections::{BTreeSet, HashMap};
use std::fmt;
use std::path::{Component, Path, PathBuf};
use std::time::{Duration, Instant};

/// The book's root (`book.toml`, and the chapters under `src/`), from the workspace root.
const BOOK: &str = "docs";

/// Pages of the built book whose links are not checked, and why:
/// - `print.html` repeats every chapter with its links rewritten to anchors of that one
///   page, so a broken link would be reported a second time, at a line nobody edits;
/// - `404.html` is mdBook's own page, whose links are relative to the site's root (its
///   `<base href>`), wherever the page is asked for, not to its file.
const SKIPPED_PAGES: &[&str] = &["print.html", "404.html"];

/// The default time limit of each example's command, seconds.
const EXAMPLE_TIME_LIMIT_S: u64 = 600;

/// What to check.
#[derive(clap::Args)]
pub struct Options {
    /// Run the examples of this Markdown file only (repeatable); the book, the API docs and
    /// every link are still checked
    #[arg(long = "file", value_name = "PATH", conflicts_with = "no_examples")]
    files: Vec<PathBuf>,
    /// Run no example: build the book and the API docs and check the links only (a quick
    /// check while writing; the check command never passes it)
    #[arg(long)]
    no_examples: bool,
    /// Time limit of each example's command, seconds (its process group is killed then)
    #[arg(long, value_name = "SECS", default_value_t = EXAMPLE_TIME_LIMIT_S)]
    time_limit: u64,
}

impl Options {
    /// The options of the check command's stage: everything.
    pub fn ci() -> Self {
        Self {
            files: Vec::new(),
            no_examples: false,
            time_limit: EXAMPLE_TIME_LIMIT_S,
        }
    }
}

/// `cargo xtask book`'s options.
#[derive(clap::Args)]
pub struct BookOptions {
    /// Open the book in the browser (`mdbook build --open`)
    #[arg(long)]
    open: bool,
}

/// Runs the check command's `docs` stage (see the module's documentation).
///
/// # Errors
/// mdBook is missing or fails, or (after every later step has run) `cargo doc` fails, a
/// link is broken, or an example does not print what it shows.
pub fn run(options: &Options) -> Result {
    let sources = markdown_files()?;
    // A wrong --file fails before anything is built.
    let examples = if options.no_examples {
        Vec::new()
    } else {
        chosen(&sources, &options.files)?
    };
    crate::setup::require_mdbook()?;
    let book = build_book(false)?;
    let mut failed = Vec::new();
    // The crate pages it leaves behind are checked even when it fails.
    if let Err(e) = Cmd::new("cargo")
        .args(["doc", "--workspace", "--no-deps", "--keep-going"])
        .env("RUSTDOCFLAGS", "-D warnings")
        .run()
    {
        failed.push(format!("{e} (its warnings are above)"));
    }
    if let Err(e) = check_links(&book, &sources) {
        failed.push(e);
    }
    if options.no_examples {
        println!("docs: examples not run (--no-examples)");
    } else if let Err(e) = run_examples(&examples, Duration::from_secs(options.time_limit)) {
        failed.push(e);
    }
    if failed.is_empty() {
        Ok(())
    } else {
        Err(failed.join("\n\n"))
    }
}

/// `cargo xtask book`: builds the book (installing mdBook if missing), checks every link,
/// and prints where the book is.
///
/// # Errors
/// mdBook cannot be installed or fails, or a link is broken.
pub fn book(options: &BookOptions) -> Result {
    crate::setup::mdbook()?;
    let book = build_book(options.open)?;
    let checked = check_links(&book, &markdown_files()?);
    println!("docs: the book is {}", shown(&book.join("index.html")));
    checked
}

/// Builds the book with mdBook (`--open`: and opens it); returns the directory of its
/// pages.
fn build_book(open: bool) -> Result<PathBuf> {
    let dir = root().join(BOOK);
    let config = dir.join("book.toml");
    if !config.is_file() {
        return Err(format!(
            "{} not found: the book's configuration, beside its chapters in {BOOK}/src/",
            shown(&config)
        ));
    }
    // mdBook would write a SUMMARY.md of its own into the sources if there were none.
    let summary = dir.join("src").join("SUMMARY.md");
    if !summary.is_file() {
        return Err(format!(
            "{} not found: the book's table of contents",
            shown(&summary)
        ));
    }
    // Given on the command line, so that the book lands beside the API docs wherever the
    // target directory is (`book.toml`'s `build-dir` says the same for `mdbook serve`).
    let out = target_dir().join("book");
    let mut mdbook = Cmd::new("mdbook").arg("build").arg("--dest-dir").arg(&out);
    if open {
        mdbook = mdbook.arg("--open");
    }
    mdbook.arg(BOOK).run()?;
    if out.join("index.html").is_file() {
        Ok(out)
    } else {
        Err(format!(
            "mdbook build wrote no index.html in {}",
            shown(&out)
        ))
    }
}

/// The Markdown files whose links and examples are checked: README.md, then every `.md`
/// file under `docs/src/`, in path order.
fn markdown_files() -> Result<Vec<PathBuf>> {
    let mut files = vec![root().join("README.md")];
    let mut chapters = Vec::new();
    walk(&root().join(BOOK).join("src"), &mut chapters)?;
    chapters.retain(|f| f.extension().is_some_and(|e| e == "md"));
    chapters.sort();
    files.extend(chapters);
    Ok(files)
}

/// Every file under `dir`, recursively (not following symbolic links).
fn walk(dir: &Path, files: &mut Vec<PathBuf>) -> Result {
    let entries =
        std::fs::read_dir(dir).map_err(|e| format!("reading directory {}: {e}", shown(dir)))?;
    for entry in entries {
        let entry = entry.map_err(|e| format!("reading directory {}: {e}", shown(dir)))?;
        let kind = entry
            .file_type()
            .map_err(|e| format!("{}: {e}", shown(&entry.path())))?;
        if kind.is_dir() {
            walk(&entry.path(), files)?;
        } else if kind.is_file() {
            files.push(entry.path());
        }
    }
    Ok(())
}

/// `--file`: the Markdown files whose examples run (all of them when none is named).
fn chosen(sources: &[PathBuf], wanted: &[PathBuf]) -> Result<Vec<PathBuf>> {
    if wanted.is_empty() {
        return Ok(sources.to_vec());
    }
    let canonical = |p: &Path| std::fs::canonicalize(p).ok();
    let known: Vec<(Option<PathBuf>, &PathBuf)> =
        sources.iter().map(|s| (canonical(s), s)).collect();
    let mut files = Vec::new();
    for file in wanted {
        // As given (from where the command runs), or from the workspace root.
        let found = [file.clone(), root().join(file)].iter().find_map(|p| {
            let p = canonical(p)?;
            known
                .iter()
                .find(|(k, _)| k.as_ref() == Some(&p))
                .map(|(_, s)| (*s).clone())
        });
        match found {
            Some(source) if !files.contains(&source) => files.push(source),
            Some(_) => {}
            None => {
                return Err(format!(
                    "--file {}: not one of the Markdown files whose examples are checked \
                     (README.md and {BOOK}/src/**/*.md)",
                    file.display()
                ))
            }
        }
    }
    Ok(files)
}

/// A path as shown in messages: from the workspace root when it is inside it.
fn shown(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// `path` with `.` and `..` resolved by their names (no file system access).
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => match out.components().next_back() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                // `/..` is `/`.
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(".."),
            },
            other => out.push(other),
        }
    }
    out
}

// ---------------------------------------------------------------------------------------
// Markdown: fences, code spans, links, headings

/// 1-based line numbers of byte offsets in a text.
struct Lines(Vec<usize>);

impl Lines {
    fn new(text: &str) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Self(starts)
    }

    /// The line of the byte at `offset`.
    fn of(&self, offset: usize) -> usize {
        self.0.partition_point(|&start| start <= offset)
    }
}

/// A fenced code block: the index of its opening line and of its closing line (the number
/// of lines when it runs to the end of the text), its info string, and the opening fence's
/// indentation.
#[derive(Debug, PartialEq)]
struct Fence {
    open: usize,
    close: usize,
    info: String,
    indent: usize,
}

/// The fenced code blocks among `lines` (a fence may be indented, as in a list item).
fn fences(lines: &[&str]) -> Vec<Fence> {
    let mut found = Vec::new();
    let mut index = 0;
    while index < lines.len() {
        let Some((mark, length, indent, info)) = fence_opening(lines[index]) else {
            index += 1;
            continue;
        };
        let closes = |line: &&str| {
            let line = line.trim();
            line.len() >= length && line.chars().all(|c| c == mark)
        };
        let close = lines[index + 1..]
            .iter()
            .position(closes)
            .map_or(lines.len(), |k| index + 1 + k);
        found.push(Fence {
            open: index,
            close,
            info,
            indent,
        });
        index = close + 1;
    }
    found
}

/// A fence's character, length, indentation and info string, if `line` opens a fence.
fn fence_opening(line: &str) -> Option<(char, usize, usize, String)> {
    let text = line.trim_start_matches([' ', '\t']);
    let mark = text.chars().next().filter(|c| matches!(c, '`' | '~'))?;
    let length = text.chars().take_while(|&c| c == mark).count();
    let info = text[length..].trim();
    // "```a```" on one line is a code span.
    if length < 3 || (mark == '`' && info.contains('`')) {
        return None;
    }
    Some((mark, length, line.len() - text.len(), info.to_string()))
}

/// Whether each line of `lines` belongs to a fenced code block (its fences included).
fn fenced(lines: &[&str]) -> Vec<bool> {
    let mut inside = vec![false; lines.len()];
    for fence in fences(lines) {
        let last = fence.close.min(lines.len() - 1);
        for flag in &mut inside[fence.open..=last] {
            *flag = true;
        }
    }
    inside
}

/// The Markdown text with what is not prose blanked out, every byte's line kept: fenced
/// code blocks become empty lines; code spans and HTML comments become spaces.
fn prose(text: &str) -> String {
    let lines: Vec<&str> = text.split('\n').collect();
    let inside = fenced(&lines);
    let kept: Vec<&str> = lines
        .iter()
        .zip(&inside)
        .map(|(line, fenced)| if *fenced { "" } else { *line })
        .collect();
    let mut bytes = kept.join("\n").into_bytes();
    let blank = |bytes: &mut [u8]| {
        for b in bytes.iter_mut().filter(|b| **b != b'\n') {
            *b = b' ';
        }
    };
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'`' => {
                let run = run_length(&bytes, i, b'`');
                match code_span_end(&bytes, i + run, run) {
                    Some(end) => {
                        blank(&mut bytes[i..end]);
                        i = end;
                    }
                    None => i += run,
                }
            }
            b'<' if bytes[i..].starts_with(b"<!--") => {
                let end = find(&bytes, i + 4, b"-->").map_or(bytes.len(), |k| k + 3);
                blank(&mut bytes[i..end]);
                i = end;
            }
            _ => i += 1,
        }
    }
    // Only ASCII bytes were replaced, and whole characters: still UTF-8.
    String::from_utf8_lossy(&bytes).into_owned()
}

/// How many `byte`s follow each other from `at`.
fn run_length(bytes: &[u8], at: usize, byte: u8) -> usize {
    bytes[at..].iter().take_while(|&&b| b == byte).count()
}

/// The first offset of `needle` in `bytes` from `from`.
fn find(bytes: &[u8], from: usize, needle: &[u8]) -> Option<usize> {
    bytes
        .get(from..)?
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|k| from + k)
}

/// The end of a code span opened by `run` backticks, its content starting at `from`: just
/// after the next run of exactly `run` backticks, unless a blank line (the paragraph's end)
/// comes first.
fn code_span_end(bytes: &[u8], from: usize, run: usize) -> Option<usize> {
    let mut j = from;
    while j < bytes.len() {
        match bytes[j] {
            b'`' => {
                let length = run_length(bytes, j, b'`');
                if length == run {
                    return Some(j + length);
                }
                j += length;
            }
            b'\n' => {
                let rest = &bytes[j + 1..];
                let line = rest.split(|&b| b == b'\n').next().unwrap_or(rest);
                if line.iter().all(u8::is_ascii_whitespace) {
                    return None;
                }
                j += 1;
            }
            _ => j += 1,
        }
    }
    None
}

/// A link found in a Markdown or HTML text: its line and its target as written (escapes
/// and entities resolved), or why what looks like a link cannot be one.
#[derive(Debug, PartialEq)]
struct Link {
    line: usize,
    target: String,
    malformed: Option<String>,
}

/// The links of a Markdown text: inline links and images (`[text](target "title")`,
/// `![alt](<target with spaces>)`), link reference definitions (`[label]: target`), and
/// the `href` of `<a>` and `src` of `<img>` tags, outside code spans, fenced code blocks
/// and HTML comments.
fn markdown_links(text: &str) -> Vec<Link> {
    let prose = prose(text);
    let bytes = prose.as_bytes();
    let lines = Lines::new(&prose);
    let mut links = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => {
                i += 2;
                continue;
            }
            b'[' => {
                if let Some(close) = closing_bracket(bytes, i) {
                    let label = &prose[i + 1..close];
                    match bytes.get(close + 1) {
                        Some(b'(') => links.push(inline_target(&prose, close + 2, &lines)),
                        Some(b':') if starts_line(bytes, i) && !label.starts_with('^') => {
                            links.extend(definition_target(&prose, close + 2, &lines));
                        }
                        _ => {}
                    }
                }
            }
            b'<' => {
                if let Some((tag, _)) = tag_at(&prose, i) {
                    let attribute = match tag.name.as_str() {
                        "a" => "href",
                        "img" => "src",
                        _ => "",
                    };
                    links.extend(
                        tag.attributes
                            .into_iter()
                            .filter(|(name, _)| name == attribute)
                            .map(|(_, target)| Link {
                                line: lines.of(i),
                                target,
                                malformed: None,
                            }),
                    );
                }
            }
            _ => {}
        }
        i += 1;
    }
    links
}

/// The `]` closing the `[` at `open` (brackets nest; escapes count), unless a blank line
/// comes first.
fn closing_bracket(bytes: &[u8], open: usize) -> Option<usize> {
    let mut depth = 0usize;
    let mut j = open + 1;
    while j < bytes.len() {
        match bytes[j] {
            b'\\' => j += 1,
            b'[' => depth += 1,
            b']' if depth == 0 => return Some(j),
            b']' => depth -= 1,
            b'\n'
                if bytes[j + 1..]
                    .split(|&b| b == b'\n')
                    .next()
                    .is_some_and(|l| l.iter().all(u8::is_ascii_whitespace)) =>
            {
                return None
            }
            _ => {}
        }
        j += 1;
    }
    None
}

/// Whether only up to three spaces come before `at` on its line.
fn starts_line(bytes: &[u8], at: usize) -> bool {
    let before = &bytes[..at];
    let start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |k| k + 1);
    at - start <= 3 && before[start..].iter().all(|&b| b == b' ')
}

/// Skips spaces and tabs, and at most one line end, from `at`.
fn skip_space(bytes: &[u8], mut at: usize) -> usize {
    let mut newline = false;
    while let Some(&b) = bytes.get(at) {
        match b {
            b' ' | b'\t' | b'\r' => at += 1,
            b'\n' if !newline => {
                newline = true;
                at += 1;
            }
            _ => break,
        }
    }
    at
}

/// A link destination starting at `at`: `<...>` (no line end inside) or a run without
/// spaces in which parentheses balance. Returns its text and the offset after it, or why
/// there is none.
fn destination(text: &str, at: usize) -> std::result::Result<(String, usize), String> {
    let bytes = text.as_bytes();
    if bytes.get(at) == Some(&b'<') {
        let mut j = at + 1;
        while let Some(&b) = bytes.get(j) {
            match b {
                b'\\' => j += 2,
                b'>' => return Ok((unescape(&text[at + 1..j]), j + 1)),
                b'<' | b'\n' => break,
                _ => j += 1,
            }
        }
        return Err("`<` opens a target that no `>` ends on its line".into());
    }
    let mut depth = 0usize;
    let mut j = at;
    while let Some(&b) = bytes.get(j) {
        match b {
            b'\\' => j += 2,
            b'(' => {
                depth += 1;
                j += 1;
            }
            b')' if depth == 0 => break,
            b')' => {
                depth -= 1;
                j += 1;
            }
            b if b.is_ascii_whitespace() || b.is_ascii_control() => break,
            _ => j += 1,
        }
    }
    let end = j.min(text.len());
    Ok((unescape(&text[at..end]), end))
}

/// The target of an inline link whose `(` ends just before `at`: `(target)`,
/// `(target "title")`, `(<target>)`; a malformed one (a space in the target, a title that
/// does not end) is returned as such, since it shows as text.
fn inline_target(text: &str, at: usize, lines: &Lines) -> Link {
    let bytes = text.as_bytes();
    let start = skip_space(bytes, at);
    let line = lines.of(start);
    let written = || {
        let rest = &text[start..];
        rest[..rest.find([')', '\n']).unwrap_or(rest.len())].to_string()
    };
    let malformed = |why: String| Link {
        line,
        target: written(),
        malformed: Some(why),
    };
    let (target, end) = match destination(text, start) {
        Ok(found) => found,
        Err(why) => return malformed(why),
    };
    let mut j = skip_space(bytes, end);
    if let Some(&open) = bytes.get(j).filter(|b| matches!(b, b'"' | b'\'' | b'(')) {
        let close = if open == b'(' { b')' } else { open };
        j += 1;
        while let Some(&b) = bytes.get(j) {
            if b == b'\\' {
                j += 1;
            } else if b == close {
                break;
            }
            j += 1;
        }
        if j >= bytes.len() {
            return malformed("its title does not end".into());
        }
        j = skip_space(bytes, j + 1);
    }
    if bytes.get(j) == Some(&b')') {
        Link {
            line,
            target,
            malformed: None,
        }
    } else {
        malformed(
            "a space in a link target ends it, so this shows as text: write a target with \
             spaces as `<...>`, a title as `\"...\"`"
                .into(),
        )
    }
}

/// The target of a link reference definition whose `:` ends just before `at`, if any.
fn definition_target(text: &str, at: usize, lines: &Lines) -> Option<Link> {
    let start = skip_space(text.as_bytes(), at);
    let line = lines.of(start);
    match destination(text, start) {
        Ok((target, _)) if target.is_empty() => None,
        Ok((target, _)) => Some(Link {
            line,
            target,
            malformed: None,
        }),
        Err(why) => Some(Link {
            line,
            target: text[start..].lines().next().unwrap_or("").to_string(),
            malformed: Some(why),
        }),
    }
}

/// Markdown backslash escapes resolved (`\(` is `(`).
fn unescape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match chars.peek() {
            Some(&next) if c == '\\' && next.is_ascii_punctuation() => {
                out.push(next);
                chars.next();
            }
            _ => out.push(c),
        }
    }
    out
}

/// The anchors of a Markdown text's headings (ATX `# ...` and setext, outside fenced code
/// blocks), in order, as the repository's web view and mdBook make them (see [`slug`]): a
/// repeated anchor gets `-1`, `-2`, ...
fn heading_anchors(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let inside = fenced(&lines);
    let mut used = BTreeSet::new();
    let mut anchors = Vec::new();
    let mut paragraph: Vec<&str> = Vec::new();
    for (line, fenced) in lines.iter().zip(inside) {
        let content = line.trim_start();
        let indented = line.len() - content.len() > 3;
        let heading = if fenced || indented {
            None
        } else if let Some(title) = atx_heading(content) {
            Some(title.to_string())
        } else if setext_underline(content) && !paragraph.is_empty() {
            Some(paragraph.join(" "))
        } else {
            None
        };
        if let Some(title) = heading {
            anchors.push(unique(slug(&heading_text(&title)), &mut used));
            paragraph.clear();
        } else if fenced || content.is_empty() || !can_be_setext(content) {
            paragraph.clear();
        } else {
            paragraph.push(content);
        }
    }
    anchors
}

/// The title of an ATX heading (`## Title ##`).
fn atx_heading(line: &str) -> Option<&str> {
    let level = line.chars().take_while(|&c| c == '#').count();
    let rest = &line[level..];
    if !(1..=6).contains(&level) || !(rest.is_empty() || rest.starts_with([' ', '\t'])) {
        return None;
    }
    let rest = rest.trim();
    // A closing sequence of `#`s, after a space.
    let without = rest.trim_end_matches('#');
    Some(if without.is_empty() || without.ends_with([' ', '\t']) {
        without.trim_end()
    } else {
        rest
    })
}

/// Whether `line` underlines a setext heading (`===` or `---`).
fn setext_underline(line: &str) -> bool {
    let line = line.trim_end();
    !line.is_empty() && (line.chars().all(|c| c == '=') || line.chars().all(|c| c == '-'))
}

/// Whether a line can be the text of a setext heading (not a list item, quote, table row
/// or HTML).
fn can_be_setext(line: &str) -> bool {
    let numbered = line
        .split_once(['.', ')'])
        .is_some_and(|(n, _)| !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()));
    !(numbered || line.starts_with(['-', '*', '+', '>', '|', '<', '#']))
}

/// A heading's text as rendered, without its Markdown: code spans keep their content,
/// links and images their text, HTML tags go, escapes are resolved, and `*`/`_` that mark
/// emphasis go (an `_` between two letters or digits stays, as in `snake_case`).
fn heading_text(markdown: &str) -> String {
    let chars: Vec<char> = markdown.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        match c {
            '\\' if chars.get(i + 1).is_some_and(char::is_ascii_punctuation) => {
                out.push(chars[i + 1]);
                i += 2;
            }
            '`' => {
                let run = chars[i..].iter().take_while(|&&c| c == '`').count();
                let content = i + run;
                let end = (content..chars.len()).find(|&j| {
                    chars[j..].iter().take_while(|&&c| c == '`').count() == run
                        && (j == 0 || chars[j - 1] != '`')
                });
                match end {
                    Some(end) => {
                        let code: String = chars[content..end].iter().collect();
                        // One space on each side is padding.
                        let code = match code.strip_prefix(' ').and_then(|c| c.strip_suffix(' ')) {
                            Some(inner) if !inner.trim().is_empty() => inner.to_string(),
                            _ => code,
                        };
                        out.push_str(&code);
                        i = end + run;
                    }
                    None => {
                        out.extend(&chars[i..content]);
                        i = content;
                    }
                }
            }
            '<' => {
                let rest: String = chars[i..].iter().collect();
                let tag_end = tag_at(&rest, 0).map(|(_, end)| end).or_else(|| {
                    rest.starts_with("</")
                        .then(|| rest.find('>').map(|k| k + 1))
                        .flatten()
                });
                match tag_end {
                    Some(end) => i += rest[..end].chars().count(),
                    None => {
                        out.push(c);
                        i += 1;
                    }
                }
            }
            // A link's or image's text stays, its target goes.
            ']' if chars.get(i + 1) == Some(&'(') => {
                let close = (i + 2..chars.len()).find(|&j| chars[j] == ')');
                i = close.map_or(i + 1, |j| j + 1);
            }
            '[' | ']' | '*' => i += 1,
            '!' if chars.get(i + 1) == Some(&'[') => i += 1,
            '_' => {
                let run = chars[i..].iter().take_while(|&&c| c == '_').count();
                let inside_word = i > 0
                    && chars[i - 1].is_alphanumeric()
                    && chars.get(i + run).is_some_and(|c| c.is_alphanumeric());
                if inside_word {
                    out.extend(&chars[i..i + run]);
                }
                i += run;
            }
            _ => {
                out.push(c);
                i += 1;
            }
        }
    }
    decode_entities(&out)
}

/// A heading's anchor, as GitHub and mdBook compute it from the heading's text: lower-case;
/// letters, digits, `-` and `_` kept; each space a `-`; every other character dropped.
fn slug(text: &str) -> String {
    text.trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                Some(c)
            } else if c.is_whitespace() {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// `anchor`, or `anchor-1`, `anchor-2`, ... when it is taken (as mdBook does).
fn unique(anchor: String, used: &mut BTreeSet<String>) -> String {
    if used.insert(anchor.clone()) {
        return anchor;
    }
    let mut n = 1;
    loop {
        let candidate = format!("{anchor}-{n}");
        if used.insert(candidate.clone()) {
            return candidate;
        }
        n += 1;
    }
}

// ---------------------------------------------------------------------------------------
// HTML: tags, links and ids

/// An HTML tag: its name and attributes (names lower-case, values with entities decoded).
struct Tag {
    name: String,
    attributes: Vec<(String, String)>,
}

/// The start tag at `at` (a `<` followed by a letter) and the offset after its `>`, if it
/// is one.
fn tag_at(html: &str, at: usize) -> Option<(Tag, usize)> {
    let bytes = html.as_bytes();
    let mut i = at + 1;
    if !bytes.get(i)?.is_ascii_alphabetic() {
        return None;
    }
    let name_end = i + html[i..].find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))?;
    let name = html[i..name_end].to_ascii_lowercase();
    i = name_end;
    let mut attributes = Vec::new();
    loop {
        while bytes.get(i)?.is_ascii_whitespace() || bytes[i] == b'/' {
            i += 1;
        }
        if bytes[i] == b'>' {
            return Some((Tag { name, attributes }, i + 1));
        }
        let start = i;
        while let Some(&b) = bytes.get(i) {
            if b.is_ascii_whitespace() || matches!(b, b'=' | b'>' | b'/') {
                break;
            }
            i += 1;
        }
        if i == start {
            // A stray character (`=` with no name): not an attribute.
            i += 1;
            continue;
        }
        let attribute = html[start..i].to_ascii_lowercase();
        while bytes.get(i)?.is_ascii_whitespace() {
            i += 1;
        }
        let mut value = "";
        if bytes[i] == b'=' {
            i += 1;
            while bytes.get(i)?.is_ascii_whitespace() {
                i += 1;
            }
            let quote = bytes[i];
            if matches!(quote, b'"' | b'\'') {
                let end = i + 1 + html[i + 1..].find(quote as char)?;
                value = &html[i + 1..end];
                i = end + 1;
            } else {
                let start = i;
                while bytes
                    .get(i)
                    .is_some_and(|b| !b.is_ascii_whitespace() && *b != b'>')
                {
                    i += 1;
                }
                value = &html[start..i];
            }
        }
        attributes.push((attribute, decode_entities(value)));
    }
}

/// Every start tag of an HTML page with its line, comments and the content of `<script>`
/// and `<style>` skipped.
fn tags(html: &str) -> Vec<(usize, Tag)> {
    let lines = Lines::new(html);
    let mut found = Vec::new();
    let mut i = 0;
    while let Some(k) = html[i..].find('<') {
        let at = i + k;
        if html[at..].starts_with("<!--") {
            i = html[at..].find("-->").map_or(html.len(), |e| at + e + 3);
            continue;
        }
        let Some((tag, end)) = tag_at(html, at) else {
            i = at + 1;
            continue;
        };
        i = end;
        if matches!(tag.name.as_str(), "script" | "style") {
            let close = format!("</{}", tag.name);
            i = html.as_bytes()[i..]
                .windows(close.len())
                .position(|w| w.eq_ignore_ascii_case(close.as_bytes()))
                .map_or(html.len(), |e| i + e);
        }
        found.push((lines.of(at), tag));
    }
    found
}

/// The links of an HTML page: every `href` and `src`, with its line (a link repeated on
/// its line counted once: mdBook writes each image twice).
fn html_links(html: &str) -> Vec<Link> {
    let mut links: Vec<Link> = tags(html)
        .into_iter()
        .flat_map(|(line, tag)| {
            tag.attributes
                .into_iter()
                .filter(|(name, _)| name == "href" || name == "src")
                .map(move |(_, target)| Link {
                    line,
                    target,
                    malformed: None,
                })
        })
        .collect();
    links.dedup();
    links
}

/// What a fragment can name in an HTML page: every `id`, and the `name` of each `<a>`.
fn html_ids(html: &str) -> BTreeSet<String> {
    tags(html)
        .into_iter()
        .flat_map(|(_, tag)| {
            let anchor = tag.name == "a";
            tag.attributes
                .into_iter()
                .filter(move |(name, _)| name == "id" || (anchor && name == "name"))
                .map(|(_, id)| id)
        })
        .collect()
}

/// HTML character references resolved (`&amp;`, `&quot;`, `&#39;`, `&#x2F;`, ...); unknown
/// ones are kept as written.
fn decode_entities(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(k) = rest.find('&') {
        out.push_str(&rest[..k]);
        rest = &rest[k..];
        let end = rest[1..]
            .char_indices()
            .take(10)
            .find(|(_, c)| *c == ';')
            .map(|(k, _)| k);
        let decoded = end.and_then(|end| {
            let name = &rest[1..=end];
            let c = match name {
                "amp" => Some('&'),
                "lt" => Some('<'),
                "gt" => Some('>'),
                "quot" => Some('"'),
                "apos" => Some('\''),
                "nbsp" => Some('\u{a0}'),
                _ => {
                    let number = name.strip_prefix('#')?;
                    let code = match number.strip_prefix(['x', 'X']) {
                        Some(hex) => u32::from_str_radix(hex, 16).ok()?,
                        None => number.parse().ok()?,
                    };
                    char::from_u32(code)
                }
            }?;
            Some((c, end + 2))
        });
        match decoded {
            Some((c, length)) => {
                out.push(c);
                rest = &rest[length..];
            }
            None => {
                out.push('&');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// `%XX` escapes of a URL's path or fragment resolved (invalid ones are kept).
fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match hex {
            Some(byte) if bytes[i] == b'%' => {
                out.push(byte);
                i += 3;
            }
            _ => {
                out.push(bytes[i]);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

// ---------------------------------------------------------------------------------------
// Link checking

/// A broken link: where, what, why.
#[derive(Debug, PartialEq)]
struct Broken {
    file: String,
    line: usize,
    target: String,
    why: String,
}

impl fmt::Display for Broken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}: broken link `{}`: {}",
            self.file, self.line, self.target, self.why
        )
    }
}

/// What is at a path.
#[derive(Clone, Copy, PartialEq)]
enum Entry {
    Missing,
    Dir,
    File,
}

/// Where the checks find files: the disk, or a test's files.
trait Files {
    /// What is at `path`.
    fn entry(&self, path: &Path) -> Entry;
    /// The text of the file at `path`.
    fn text(&self, path: &Path) -> Option<String>;
}

/// The files on disk.
struct Disk;

impl Files for Disk {
    fn entry(&self, path: &Path) -> Entry {
        match std::fs::metadata(path) {
            Ok(m) if m.is_dir() => Entry::Dir,
            Ok(_) => Entry::File,
            Err(_) => Entry::Missing,
        }
    }

    fn text(&self, path: &Path) -> Option<String> {
        std::fs::read_to_string(path).ok()
    }
}

/// The anchors of each file a link's fragment names, read once: a Markdown file's heading
/// anchors, an HTML page's ids.
struct Anchors<'a> {
    files: &'a dyn Files,
    known: HashMap<PathBuf, BTreeSet<String>>,
}

impl<'a> Anchors<'a> {
    fn new(files: &'a dyn Files) -> Self {
        Self {
            files,
            known: HashMap::new(),
        }
    }

    /// Whether `fragment` names a place in the file at `path`.
    fn has(&mut self, path: &Path, fragment: &str) -> bool {
        let files = self.files;
        self.known
            .entry(path.to_path_buf())
            .or_insert_with(|| {
                let text = files.text(path).unwrap_or_default();
                match path.extension().and_then(|e| e.to_str()) {
                    Some("md") => heading_anchors(&text).into_iter().collect(),
                    Some("html" | "htm") => html_ids(&text),
                    _ => BTreeSet::new(),
                }
            })
            .contains(fragment)
    }
}

/// A link's target split: path (percent-decoded), and fragment (percent-decoded; `None`
/// without `#`); `None` for a target with a scheme (`https:`, `mailto:`) or a host (`//`),
/// which is not checked.
fn relative(target: &str) -> Option<(String, Option<String>)> {
    let scheme = target.split_once(':').is_some_and(|(s, _)| {
        s.starts_with(|c: char| c.is_ascii_alphabetic())
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
    });
    if scheme || target.starts_with("//") {
        return None;
    }
    let (rest, fragment) = match target.split_once('#') {
        Some((rest, fragment)) => (rest, Some(percent_decode(fragment))),
        None => (target, None),
    };
    let path = rest.split('?').next().unwrap_or("");
    Some((percent_decode(path), fragment))
}

/// A link to a local file that resolved: where it was written and what it names (checked
/// afterwards against the files git ignores).
struct Local {
    file: String,
    line: usize,
    target: String,
    path: PathBuf,
}

/// The broken links of the Markdown file `file` (with text `text`) in the repository at
/// `root`, as the repository's web view reads them: a relative target must name a file or
/// directory of the repository, and a fragment on a Markdown file (or alone) one of its
/// heading anchors. Returns them, the links to local files that exist, and how many links
/// were checked (those without a scheme).
fn check_markdown(
    file: &Path,
    text: &str,
    root: &Path,
    anchors: &mut Anchors,
) -> (Vec<Broken>, Vec<Local>, usize) {
    let name = file
        .strip_prefix(root)
        .unwrap_or(file)
        .display()
        .to_string();
    // mdBook's draft chapters are links with no target.
    let summary = file.file_name().is_some_and(|n| n == "SUMMARY.md");
    let mut broken = Vec::new();
    let mut local = Vec::new();
    let mut count = 0;
    for link in markdown_links(text) {
        let mut fail = |why: String| {
            broken.push(Broken {
                file: name.clone(),
                line: link.line,
                target: link.target.clone(),
                why,
            });
        };
        if let Some(why) = &link.malformed {
            count += 1;
            fail(why.clone());
            continue;
        }
        let Some((path, fragment)) = relative(&link.target) else {
            continue;
        };
        count += 1;
        if path.is_empty() {
            match &fragment {
                Some(f) if !f.is_empty() && !anchors.has(file, f) => fail(format!(
                    "no heading of {name} has the anchor `{f}`{}",
                    nearest(anchors, file, f)
                )),
                Some(_) => {}
                None if summary => {}
                None => fail("the target is empty".into()),
            }
            continue;
        }
        if path.starts_with('/') {
            fail(
                "an absolute path reads differently on the repository's web view (from the \
                 repository's root) and in the book (from the site's root): write it \
                 relative to this file"
                    .into(),
            );
            continue;
        }
        let folder = file.parent().unwrap_or(root);
        let resolved = normalize(&folder.join(&path));
        let Ok(inside) = resolved.strip_prefix(root) else {
            fail("it leaves the repository".into());
            continue;
        };
        match anchors.files.entry(&resolved) {
            Entry::Missing => fail(format!("no file {}", inside.display())),
            Entry::Dir => {}
            Entry::File => {
                let markdown = resolved.extension().is_some_and(|e| e == "md");
                match fragment.as_deref() {
                    Some(f) if markdown && !f.is_empty() && !anchors.has(&resolved, f) => {
                        fail(format!(
                            "no heading of {} has the anchor `{f}`{}",
                            inside.display(),
                            nearest(anchors, &resolved, f)
                        ));
                    }
                    _ => {}
                }
            }
        }
        if anchors.files.entry(&resolved) != Entry::Missing {
            local.push(Local {
                file: name.clone(),
                line: link.line,
                target: link.target.clone(),
                path: inside.to_path_buf(),
            });
        }
    }
    (broken, local, count)
}

/// `" (did you mean `x`?)"` for the anchor of `path` nearest to `fragment`, if one is
/// close (a few characters apart, or containing it).
fn nearest(anchors: &mut Anchors, path: &Path, fragment: &str) -> String {
    anchors.has(path, fragment);
    let Some(known) = anchors.known.get(path) else {
        return String::new();
    };
    let close = 2.max(fragment.chars().count() / 3);
    known
        .iter()
        .map(|a| (distance(a, fragment), a))
        .filter(|(d, a)| *d <= close || (!fragment.is_empty() && a.contains(fragment)))
        .min()
        .map(|(_, a)| format!(" (did you mean `{a}`?)"))
        .unwrap_or_default()
}

/// Levenshtein distance between two strings, by characters.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (diagonal + usize::from(ca != *cb))
                .min(row[j] + 1)
                .min(above + 1);
            diagonal = above;
        }
    }
    row[b.len()]
}

/// A tree of pages a link may land in, and its name in messages.
type Site<'p> = (&'p Path, &'p str);

/// The broken links of the HTML page `page` (with text `text`): a relative target must land
/// in one of `sites` (the book, the API docs) on a file that exists (a directory's
/// `index.html`), and a fragment must be an id of that page (of this page for `#x`). Links
/// that stay inside `unchecked` are not looked at (rustdoc's own links between its pages).
fn check_html(
    page: &Path,
    text: &str,
    sites: &[Site],
    unchecked: Option<&Path>,
    anchors: &mut Anchors,
) -> (Vec<Broken>, usize) {
    let name = shown(page);
    let mut broken = Vec::new();
    let mut checked = 0;
    for link in html_links(text) {
        let Some((path, fragment)) = relative(&link.target) else {
            continue;
        };
        let mut fail = |why: String| {
            broken.push(Broken {
                file: name.clone(),
                line: link.line,
                target: link.target.clone(),
                why,
            });
        };
        let resolved = if path.is_empty() {
            page.to_path_buf()
        } else if path.starts_with('/') {
            checked += 1;
            fail("an absolute path depends on where the site is served: make it relative".into());
            continue;
        } else {
            normalize(&page.parent().unwrap_or(page).join(&path))
        };
        if let Some(api) = unchecked.filter(|u| resolved.starts_with(u)) {
            // rustdoc's own links are its business, but a link meant for the book that
            // stops one `../` short lands in the API docs, where no book is.
            if resolved.starts_with(api.join("book")) {
                checked += 1;
                fail(format!(
                    "it lands inside the API docs ({}): the book is beside them, one `../` up",
                    shown(&resolved)
                ));
            }
            continue;
        }
        checked += 1;
        let Some((site, _)) = sites.iter().find(|(root, _)| resolved.starts_with(root)) else {
            let names: Vec<&str> = sites.iter().map(|(_, n)| *n).collect();
            fail(format!(
                "it lands outside {} (on {})",
                names.join(" and "),
                shown(&resolved)
            ));
            continue;
        };
        let target = match anchors.files.entry(&resolved) {
            Entry::File => resolved,
            Entry::Dir if anchors.files.entry(&resolved.join("index.html")) == Entry::File => {
                resolved.join("index.html")
            }
            Entry::Dir => {
                fail(format!("no index.html in {}", shown(&resolved)));
                continue;
            }
            Entry::Missing => {
                let hint = if anchors.files.entry(site) == Entry::Missing {
                    format!(" ({} is not built)", shown(site))
                } else {
                    String::new()
                };
                fail(format!("no file {}{hint}", shown(&resolved)));
                continue;
            }
        };
        let html = target
            .extension()
            .is_some_and(|e| e == "html" || e == "htm");
        match fragment.as_deref() {
            Some(f) if html && !f.is_empty() && !anchors.has(&target, f) => fail(format!(
                "no id `{f}` in {}{}",
                shown(&target),
                nearest(anchors, &target, f)
            )),
            _ => {}
        }
    }
    (broken, checked)
}

/// Checks every link (see the module's documentation): of the Markdown sources, of the
/// book's pages in `book`, and of the crate pages in `target/doc` that leave the API docs;
/// lists every broken one before failing.
fn check_links(book: &Path, sources: &[PathBuf]) -> Result {
    let root = root();
    let api = target_dir().join("doc");
    let mut anchors = Anchors::new(&Disk);
    let mut broken = Vec::new();

    let mut local = Vec::new();
    let mut source_links = 0;
    for file in sources {
        let text =
            std::fs::read_to_string(file).map_err(|e| format!("reading {}: {e}", shown(file)))?;
        let (b, l, n) = check_markdown(file, &text, &root, &mut anchors);
        source_links += n;
        broken.extend(b);
        local.extend(l);
    }
    broken.extend(ignored(&local)?);

    let mut pages = Vec::new();
    walk(book, &mut pages)?;
    pages.retain(|p| {
        p.extension().is_some_and(|e| e == "html")
            && !SKIPPED_PAGES
                .iter()
                .any(|s| p.strip_prefix(book).is_ok_and(|r| r == Path::new(s)))
    });
    pages.sort();
    let mut book_links = 0;
    let sites: [Site; 2] = [(book, "the book"), (api.as_path(), "the API docs")];
    for page in &pages {
        let text =
            std::fs::read_to_string(page).map_err(|e| format!("reading {}: {e}", shown(page)))?;
        let (b, n) = check_html(page, &text, &sites, None, &mut anchors);
        book_links += n;
        broken.extend(b);
    }

    let crate_pages = crate_pages(&api)?;
    let mut api_links = 0;
    for page in &crate_pages {
        let text =
            std::fs::read_to_string(page).map_err(|e| format!("reading {}: {e}", shown(page)))?;
        let (b, n) = check_html(page, &text, &[(book, "the book")], Some(&api), &mut anchors);
        api_links += n;
        broken.extend(b);
    }

    println!(
        "docs: links: {source_links} in {} Markdown files, {book_links} in {} pages of the \
         book, {api_links} from {} crate pages to the book",
        sources.len(),
        pages.len(),
        crate_pages.len()
    );
    if broken.is_empty() {
        println!("docs: no link is broken");
        Ok(())
    } else {
        let list: Vec<String> = broken.iter().map(ToString::to_string).collect();
        Err(format!(
            "{} broken link(s) (`cargo xtask book` checks them again):\n{}",
            broken.len(),
            list.join("\n")
        ))
    }
}

/// The links among `local` that name a file git ignores (a built file, which the
/// repository's web view does not have), as broken links.
fn ignored(local: &[Local]) -> Result<Vec<Broken>> {
    if local.is_empty() {
        return Ok(Vec::new());
    }
    let listing = Cmd::new("git")
        .args([
            "ls-files",
            "--others",
            "--ignored",
            "--exclude-standard",
            "--directory",
        ])
        .capture()?;
    if !listing.success {
        println!(
            "docs: links to files git ignores not looked for (not a git checkout?): {}",
            listing.stderr.trim()
        );
        return Ok(Vec::new());
    }
    let ignored: Vec<&str> = listing.stdout.lines().collect();
    Ok(local
        .iter()
        .filter(|l| {
            let path = l.path.to_string_lossy();
            ignored.iter().any(|i| match i.strip_suffix('/') {
                Some(dir) => path == dir || path.starts_with(i),
                None => path == *i,
            })
        })
        .map(|l| Broken {
            file: l.file.clone(),
            line: l.line,
            target: l.target.clone(),
            why: format!(
                "{} is ignored by git (a built file, not in the repository)",
                l.path.display()
            ),
        })
        .collect())
}

/// The crate and module pages of the API docs: each `index.html` under a crate's directory
/// (`target/doc/cw_core/index.html`, `target/doc/cw_core/os/index.html`); none when the API
/// docs are not built.
fn crate_pages(api: &Path) -> Result<Vec<PathBuf>> {
    let Ok(entries) = std::fs::read_dir(api) else {
        return Ok(Vec::new());
    };
    let mut pages = Vec::new();
    for entry in entries {
        let dir = entry
            .map_err(|e| format!("reading directory {}: {e}", shown(api)))?
            .path();
        // rustdoc's sources pages and shared files are not crates.
        let own = dir
            .file_name()
            .is_some_and(|n| n == "src" || n == "static.files");
        if dir.join("index.html").is_file() && !own {
            let mut files = Vec::new();
            walk(&dir, &mut files)?;
            pages.extend(
                files
                    .into_iter()
                    .filter(|f| f.file_name().is_some_and(|n| n == "index.html")),
            );
        }
    }
    pages.sort();
    Ok(pages)
}

// ---------------------------------------------------------------------------------------
// Examples

/// The exit status an example expects.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Status {
    /// This exit code (`? N`; 0 when not given).
    Code(i32),
    /// Any failure: an exit code other than 0, or a signal (`? failed`).
    Failed,
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Code(code) => write!(f, "exit status {code}"),
            Self::Failed => write!(f, "a failure"),
        }
    }
}

/// One command of a transcript and what it must print.
#[derive(Debug, PartialEq)]
struct Example {
    /// The line of its `$ `.
    line: usize,
    /// The command as bash reads it (continued lines joined by their `\` and line end).
    command: String,
    status: Status,
    /// The expected output (its lines joined by `\n`).
    output: String,
}

/// The transcripts of a Markdown text: the fenced code blocks whose info string is
/// `console`, each a list of examples. In a block (indented as its fence is):
/// - a line starting with `$ ` is a command; a trailing ` \` continues it on the next line;
/// - a line `? N` right after the command gives the exit status it expects (0 when not
///   given; `? failed`: any failure); any other line starting with `? ` there is an error;
/// - the lines after that, up to the next `$ ` line or the block's end, are its output.
///
/// Errors are the line and what is wrong, each of them.
fn transcripts(text: &str) -> std::result::Result<Vec<Vec<Example>>, Vec<(usize, String)>> {
    let lines: Vec<&str> = text.lines().collect();
    let mut blocks = Vec::new();
    let mut errors = Vec::new();
    for fence in fences(&lines) {
        if fence.info.split_whitespace().next() != Some("console") {
            continue;
        }
        let body: Vec<&str> = lines[fence.open + 1..fence.close]
            .iter()
            .map(|l| strip_indent(l, fence.indent))
            .collect();
        match transcript(&body, fence.open + 2) {
            Ok(examples) => blocks.push(examples),
            Err(e) => errors.extend(e),
        }
    }
    if errors.is_empty() {
        Ok(blocks)
    } else {
        Err(errors)
    }
}

/// Up to `indent` leading spaces of `line` removed.
fn strip_indent(line: &str, indent: usize) -> &str {
    let spaces = line.len() - line.trim_start_matches(' ').len();
    &line[spaces.min(indent)..]
}

/// The command on a line starting with `$ ` (or a lone `$`).
fn command_line(line: &str) -> Option<&str> {
    line.strip_prefix("$ ").or((line == "$").then_some(""))
}

/// The examples of one `console` block, whose first line is line `first` of the file.
fn transcript(
    body: &[&str],
    first: usize,
) -> std::result::Result<Vec<Example>, Vec<(usize, String)>> {
    let mut examples = Vec::new();
    let mut errors = Vec::new();
    let mut k = 0;
    while k < body.len() {
        let Some(command) = command_line(body[k]) else {
            if !body[k].trim().is_empty() {
                errors.push((
                    first + k,
                    "a `console` block is a transcript: its first line must be a command, \
                     starting with `$ `"
                        .into(),
                ));
                // One error per block is enough: skip to the next command.
                while k < body.len() && command_line(body[k]).is_none() {
                    k += 1;
                }
                continue;
            }
            k += 1;
            continue;
        };
        let line = first + k;
        let mut text = command.to_string();
        while text.trim_end().ends_with('\\') {
            k += 1;
            match body.get(k) {
                Some(next) => {
                    text.push('\n');
                    text.push_str(next);
                }
                None => {
                    errors.push((line, "the command's last line ends with `\\`".into()));
                    break;
                }
            }
        }
        k += 1;
        if text.trim().is_empty() {
            errors.push((line, "`$` with no command".into()));
        }
        let mut status = Status::Code(0);
        if let Some(given) = body.get(k).and_then(|l| l.strip_prefix("? ")) {
            match parse_status(given.trim()) {
                Some(s) => status = s,
                None => errors.push((
                    first + k,
                    format!(
                        "`? {given}`: the expected exit status is `? N` (0 to 255) or \
                         `? failed`"
                    ),
                )),
            }
            k += 1;
        }
        // Past the end when the last line continued nowhere.
        k = k.min(body.len());
        let start = k;
        while k < body.len() && command_line(body[k]).is_none() {
            k += 1;
        }
        examples.push(Example {
            line,
            command: text,
            status,
            output: body[start..k].join("\n"),
        });
    }
    if errors.is_empty() {
        Ok(examples)
    } else {
        Err(errors)
    }
}

/// `N` (0 to 255) or `failed`.
fn parse_status(text: &str) -> Option<Status> {
    if text == "failed" {
        return Some(Status::Failed);
    }
    let code: i32 = text.parse().ok()?;
    (0..=255).contains(&code).then_some(Status::Code(code))
}

/// A command on one line, for the log: continued lines joined by a space.
fn one_line(command: &str) -> String {
    command
        .lines()
        .map(|l| l.trim().trim_end_matches('\\').trim())
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// A text's lines as compared: trailing whitespace dropped from each, trailing empty lines
/// dropped.
fn compared_lines(text: &str) -> Vec<&str> {
    let mut lines: Vec<&str> = text.lines().map(str::trim_end).collect();
    while lines.last() == Some(&"") {
        lines.pop();
    }
    lines
}

/// The line that stands for any number of lines (none included).
const ANY_LINES: &str = "...";

/// What stands for any run of characters within a line.
const ANY_TEXT: &str = "[..]";

/// Whether a command's `actual` output is the `expected` one (see [`compared_lines`]): a
/// line `...` matches zero or more whole lines, `[..]` in a line any run of characters
/// (see [`line_matches`]); everything else must be the same.
fn output_matches(expected: &str, actual: &str) -> bool {
    let pattern = compared_lines(expected);
    let lines = compared_lines(actual);
    let (mut p, mut a) = (0, 0);
    // Where to go back to when a line fails: the pattern after the last `...`, and the
    // actual line that `...` would take one more of.
    let mut back: Option<(usize, usize)> = None;
    while a < lines.len() {
        if pattern.get(p) == Some(&ANY_LINES) {
            back = Some((p + 1, a));
            p += 1;
        } else if pattern.get(p).is_some_and(|e| line_matches(e, lines[a])) {
            p += 1;
            a += 1;
        } else if let Some((after, from)) = back {
            p = after;
            a = from + 1;
            back = Some((after, from + 1));
        } else {
            return false;
        }
    }
    pattern[p..].iter().all(|e| *e == ANY_LINES)
}

/// Whether `line` is the `pattern` line, each `[..]` in it matching any run of characters.
fn line_matches(pattern: &str, line: &str) -> bool {
    let parts: Vec<&str> = pattern.split(ANY_TEXT).collect();
    let [first, middle @ .., last] = parts.as_slice() else {
        return pattern == line;
    };
    let Some(mut rest) = line.strip_prefix(first) else {
        return false;
    };
    // Each middle part at its first place is never worse than at a later one.
    for part in middle {
        match rest.find(part) {
            Some(k) => rest = &rest[k + part.len()..],
            None => return false,
        }
    }
    rest.ends_with(last)
}

/// A line diff of an expected output (with its wildcards) and the actual one: `-` lines
/// expected and missing, `+` lines printed and not expected, long runs of matching lines
/// cut short.
fn diff(expected: &str, actual: &str) -> String {
    let pattern = compared_lines(expected);
    let lines = compared_lines(actual);
    let (n, m) = (pattern.len(), lines.len());
    if (n + 1) * (m + 1) > 4_000_000 {
        return format!(
            "expected:\n{}\nactual:\n{}",
            indent(&pattern.join("\n")),
            indent(&lines.join("\n"))
        );
    }
    // cost[i][j]: fewest lines left unmatched aligning pattern[i..] with lines[j..].
    let at = |i: usize, j: usize| i * (m + 1) + j;
    let mut cost = vec![0usize; (n + 1) * (m + 1)];
    for i in (0..=n).rev() {
        for j in (0..=m).rev() {
            cost[at(i, j)] = if i == n {
                m - j
            } else if pattern[i] == ANY_LINES {
                let skip = cost[at(i + 1, j)];
                if j < m {
                    skip.min(cost[at(i, j + 1)])
                } else {
                    skip
                }
            } else {
                let mut best = cost[at(i + 1, j)] + 1;
                if j < m {
                    best = best.min(cost[at(i, j + 1)] + 1);
                    if line_matches(pattern[i], lines[j]) {
                        best = best.min(cost[at(i + 1, j + 1)]);
                    }
                }
                best
            };
        }
    }
    // Walk the cheapest alignment: (' ' | '-' | '+', line).
    let mut walked: Vec<(char, &str)> = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        let here = cost[at(i, j)];
        if i < n && pattern[i] == ANY_LINES {
            if cost[at(i + 1, j)] == here {
                i += 1;
            } else {
                walked.push((' ', lines[j]));
                j += 1;
            }
        } else if i < n
            && j < m
            && line_matches(pattern[i], lines[j])
            && cost[at(i + 1, j + 1)] == here
        {
            walked.push((' ', lines[j]));
            i += 1;
            j += 1;
        } else if i < n && cost[at(i + 1, j)] + 1 == here {
            walked.push(('-', pattern[i]));
            i += 1;
        } else {
            walked.push(('+', lines[j]));
            j += 1;
        }
    }
    // Matching lines more than two away from a change are counted, not shown.
    let near = |k: usize| {
        let from = k.saturating_sub(2);
        walked[from..(k + 3).min(walked.len())]
            .iter()
            .any(|(mark, _)| *mark != ' ')
    };
    let mut out = Vec::new();
    let mut hidden = 0;
    for (k, (mark, line)) in walked.iter().enumerate() {
        if *mark == ' ' && !near(k) {
            hidden += 1;
            continue;
        }
        if hidden > 0 {
            out.push(format!("  ({hidden} line(s) as expected)"));
            hidden = 0;
        }
        out.push(format!("{mark} {line}").trim_end().to_string());
    }
    if hidden > 0 {
        out.push(format!("  ({hidden} line(s) as expected)"));
    }
    out.join("\n")
}

/// Every line of `text` indented by two spaces.
fn indent(text: &str) -> String {
    text.lines()
        .map(|l| format!("  {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Runs every example of `files` (their commands in order), each in a bash of its own in the
/// workspace root, with stdin closed, its stdout and stderr on one pipe (in the order a
/// terminal shows them), `CARGO_TERM_QUIET=true` and `CARGO_TERM_COLOR=never` (no progress
/// lines or colours from cargo), and `limit` to finish; fails listing every example whose
/// status or output is not the one shown, after running them all.
fn run_examples(files: &[PathBuf], limit: Duration) -> Result {
    // Every transcript is read before any runs: a malformed one fails at once.
    let mut all = Vec::new();
    let mut malformed = Vec::new();
    for file in files {
        let text =
            std::fs::read_to_string(file).map_err(|e| format!("reading {}: {e}", shown(file)))?;
        match transcripts(&text) {
            Ok(blocks) => all.push((shown(file), blocks)),
            Err(errors) => malformed.extend(
                errors
                    .into_iter()
                    .map(|(line, e)| format!("{}:{line}: {e}", shown(file))),
            ),
        }
    }
    if !malformed.is_empty() {
        return Err(format!(
            "malformed `console` block(s):\n{}",
            malformed.join("\n")
        ));
    }
    let mut count = 0;
    let mut mismatches = Vec::new();
    for (file, blocks) in &all {
        for example in blocks.iter().flatten() {
            count += 1;
            print!("docs: {file}:{}: ", example.line);
            let started = Instant::now();
            // `eval`, so that stderr is on stdout's pipe before bash reads the command.
            let out = Cmd::new("bash")
                .args(["-c", "exec 2>&1; eval \"$1\"", "bash"])
                .arg(&example.command)
                .env("CARGO_TERM_QUIET", "true")
                .env("CARGO_TERM_COLOR", "never")
                .show_as(one_line(&example.command))
                .within(limit)?;
            let secs = started.elapsed().as_secs_f64();
            let actual = out.stdout + &out.stderr;
            let status_ok = match (example.status, out.code) {
                (Status::Code(want), Some(code)) => want == code,
                (Status::Failed, code) => code != Some(0),
                (Status::Code(_), None) => false,
            };
            let output_ok = output_matches(&example.output, &actual);
            let mut why = Vec::new();
            if out.timed_out {
                why.push(format!(
                    "it did not finish in {} s: its process group was killed",
                    limit.as_secs()
                ));
            } else if out.lingered {
                why.push(
                    "it exited, but processes it started kept its output open: they were \
                     killed"
                        .into(),
                );
            }
            if !status_ok && !out.timed_out {
                let got = out.code.map_or_else(
                    || "ended by a signal".into(),
                    |c| format!("exit status {c}"),
                );
                why.push(format!("{got}, expected {}", example.status));
            }
            if !output_ok {
                why.push(format!(
                    "its output is not the one shown (- shown, + printed):\n{}",
                    indent(&diff(&example.output, &actual))
                ));
            }
            if why.is_empty() {
                println!(" ok ({secs:.1} s)");
            } else {
                println!(" FAILED ({secs:.1} s)");
                mismatches.push(format!(
                    "{file}:{}: $ {}\n{}",
                    example.line,
                    one_line(&example.command),
                    indent(&why.join("\n"))
                ));
            }
        }
    }
    let with_examples = all.iter().filter(|(_, b)| b.iter().any(|e| !e.is_empty()));
    let files = match with_examples.count() {
        1 => "1 file".to_string(),
        n => format!("{n} files"),
    };
    if mismatches.is_empty() {
        println!("docs: {count} examples in {files}, every one as shown");
        Ok(())
    } else {
        println!(
            "docs: {count} examples in {files}, {} not as shown",
            mismatches.len()
        );
        Err(format!(
            "{} of {count} example(s) do not run as their file shows:\n\n{}",
            mismatches.len(),
            mismatches.join("\n\n")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn slugs_are_lower_case_letters_digits_dashes_and_underscores() {
        assert_eq!(slug("The kernel"), "the-kernel");
        assert_eq!(slug("  Padded  "), "padded");
        assert_eq!(
            slug("`--file PATH`: one chapter"),
            "--file-path-one-chapter"
        );
        assert_eq!(slug("What's new? (2.0)"), "whats-new-20");
        assert_eq!(slug("a  b"), "a--b");
        assert_eq!(slug("snake_case & more"), "snake_case--more");
        assert_eq!(slug("Über CJK 中文"), "über-cjk-中文");
        assert_eq!(slug("Emoji 🦀 here"), "emoji--here");
    }

    #[test]
    fn heading_text_drops_markdown_but_keeps_code() {
        assert_eq!(heading_text("The `os` module"), "The os module");
        assert_eq!(heading_text("`__fuzz__` corpora"), "__fuzz__ corpora");
        assert_eq!(
            heading_text("*Very* **bold** _em_ snake_case"),
            "Very bold em snake_case"
        );
        assert_eq!(heading_text("See [the book](book.md#x)"), "See the book");
        assert_eq!(
            heading_text("A <code>tag</code> &amp; more"),
            "A tag & more"
        );
        assert_eq!(heading_text(r"Escaped \* star"), "Escaped * star");
    }

    #[test]
    fn heading_anchors_follow_the_headings_skip_fences_and_number_repeats() {
        let text = "# Title #\n\n## The kernel\n\n```sh\n# not a heading\n```\n\n\
                    ## The kernel\n\nSetext\n------\n\n- item\n---\n\n#no-space\n\
                    ####### seven\n    # indented code\n## `cargo xtask docs`\n";
        assert_eq!(
            heading_anchors(text),
            [
                "title",
                "the-kernel",
                "the-kernel-1",
                "setext",
                "cargo-xtask-docs"
            ]
        );
    }

    fn targets(text: &str) -> Vec<(usize, &str)> {
        // Leaked for the test's convenience: the strings outlive the call.
        markdown_links(text)
            .into_iter()
            .map(|l| {
                assert_eq!(l.malformed, None, "{l:?}");
                (l.line, &*Box::leak(l.target.into_boxed_str()))
            })
            .collect()
    }

    #[test]
    fn links_and_images_are_found_outside_code() {
        let text = "See [a](a.md) and ![pic](img/x.png \"Title\").\n\
                    `[not](code.md)` and ``[nor](this.md) ` here``\n\
                    ```console\n$ cat [x](fenced.md)\n```\n\
                    ~~~\n[y](tilde.md)\n~~~\n\
                    <!-- [z](comment.md) -->\n\
                    [multi\nline](multi.md) [nested [b]](n.md#frag)\n\
                    [ref]: docs/ref.md \"t\"\n\
                    [^note]: a footnote, not a target\n\
                    <a href=\"html.md\">x</a> <img src='pic.png'>\n\
                    \\[escaped](no.md) [code `x`](code-in-text.md)\n";
        assert_eq!(
            targets(text),
            [
                (1, "a.md"),
                (1, "img/x.png"),
                (11, "multi.md"),
                (11, "n.md#frag"),
                (12, "docs/ref.md"),
                (14, "html.md"),
                (14, "pic.png"),
                (15, "code-in-text.md"),
            ]
        );
    }

    #[test]
    fn a_code_span_ends_at_a_run_of_the_same_length_within_its_paragraph() {
        // The lone backtick opens nothing: the paragraph ends first.
        let text = "a ` b [x](x.md)\n\nc `` d ` [in](code.md) `` [out](out.md)\n";
        assert_eq!(targets(text), [(1, "x.md"), (3, "out.md")]);
        // A code span across a line end.
        assert_eq!(targets("`a\n[b](c.md)` [d](d.md)"), [(2, "d.md")]);
    }

    #[test]
    fn an_indented_fence_in_a_list_is_skipped_too() {
        let text = "1. Run:\n\n   ```console\n   $ ls [x](no.md)\n   ```\n2. [y](y.md)\n";
        assert_eq!(targets(text), [(6, "y.md")]);
    }

    #[test]
    fn targets_in_angle_brackets_titles_and_parentheses() {
        let text = "[a](<with space.md>) [b](b.md 'single') [c](c.md (paren))\n\
                    [d](f(x).md) [e](\\(esc\\).md) [f](\n  next-line.md\n)";
        assert_eq!(
            targets(text),
            [
                (1, "with space.md"),
                (1, "b.md"),
                (1, "c.md"),
                (2, "f(x).md"),
                (2, "(esc).md"),
                (3, "next-line.md"),
            ]
        );
    }

    #[test]
    fn a_space_in_a_target_or_an_open_angle_bracket_is_refused() {
        let links = markdown_links("[a](two words.md) [b](<open.md) [c](ok.md)");
        let found: Vec<(&str, bool)> = links
            .iter()
            .map(|l| (l.target.as_str(), l.malformed.is_some()))
            .collect();
        assert_eq!(
            found,
            [("two words.md", true), ("<open.md", true), ("ok.md", false)]
        );
    }

    /// Files for the checks, in memory: path, and text (`None`: a directory).
    struct Memory(BTreeMap<PathBuf, Option<String>>);

    impl Memory {
        fn new(files: &[(&str, Option<&str>)]) -> Self {
            Self(
                files
                    .iter()
                    .map(|(p, t)| (PathBuf::from(p), t.map(str::to_string)))
                    .collect(),
            )
        }
    }

    impl Files for Memory {
        fn entry(&self, path: &Path) -> Entry {
            match self.0.get(path) {
                Some(Some(_)) => Entry::File,
                Some(None) => Entry::Dir,
                None if self.0.keys().any(|k| k.starts_with(path)) => Entry::Dir,
                None => Entry::Missing,
            }
        }

        fn text(&self, path: &Path) -> Option<String> {
            self.0.get(path).cloned().flatten()
        }
    }

    #[test]
    fn markdown_links_must_name_files_and_headings_of_the_repository() {
        let readme = "# Read me\n\n## Quick start\n\n\
                      [ok](docs/src/os.md#the-kernel) [dir](core/) [src](core/src/lib.rs#L3)\n\
                      [self](#quick-start) [bad self](#quick-star)\n\
                      [no file](docs/src/nope.md) [bad anchor](docs/src/os.md#kernel)\n\
                      [abs](/core/) [out](../elsewhere.md) [web](https://example.com/x)\n\
                      [mail](mailto:a@b.c) [query](docs/src/os.md?plain=1#the-kernel)\n\
                      [empty]() [spaced](docs/src/my%20file.md)\n";
        let os = "# OS\n\n## The kernel\n";
        let files = Memory::new(&[
            ("/r/README.md", Some(readme)),
            ("/r/docs/src/os.md", Some(os)),
            ("/r/docs/src/my file.md", Some("")),
            ("/r/core/src/lib.rs", Some("")),
        ]);
        let mut anchors = Anchors::new(&files);
        let (broken, local, checked) = check_markdown(
            Path::new("/r/README.md"),
            readme,
            Path::new("/r"),
            &mut anchors,
        );
        let found: Vec<(usize, &str, &str)> = broken
            .iter()
            .map(|b| (b.line, b.target.as_str(), b.why.as_str()))
            .collect();
        assert_eq!(
            found,
            [
                (6, "#quick-star", "no heading of README.md has the anchor `quick-star` (did you mean `quick-start`?)"),
                (7, "docs/src/nope.md", "no file docs/src/nope.md"),
                (7, "docs/src/os.md#kernel", "no heading of docs/src/os.md has the anchor `kernel` (did you mean `the-kernel`?)"),
                (8, "/core/", "an absolute path reads differently on the repository's web view (from the repository's root) and in the book (from the site's root): write it relative to this file"),
                (8, "../elsewhere.md", "it leaves the repository"),
                (10, "", "the target is empty"),
            ]
        );
        assert_eq!(broken[0].to_string(), "README.md:6: broken link `#quick-star`: no heading of README.md has the anchor `quick-star` (did you mean `quick-start`?)");
        assert_eq!(checked, 12);
        let resolved: Vec<PathBuf> = local.into_iter().map(|l| l.path).collect();
        assert_eq!(
            resolved,
            [
                "docs/src/os.md",
                "core",
                "core/src/lib.rs",
                "docs/src/os.md",
                "docs/src/os.md",
                "docs/src/my file.md"
            ]
            .map(PathBuf::from)
        );
    }

    #[test]
    fn html_links_must_land_on_pages_and_ids_of_the_book_or_the_api_docs() {
        let intro = "<html><head><link href=\"css/a.css\"><script src=\"book.js\"></script>\n\
                     <script>let s = '<a href=\"in-script.html\">';</script></head>\n\
                     <body><h1 id=\"intro\">Intro</h1>\n\
                     <a href=\"os.html#the-kernel\">k</a> <a href='os.html#nope'>n</a>\n\
                     <a href=\"#intro\">top</a> <a href=\"#outro\">x</a> <a href=\"gone.html\">g</a>\n\
                     <a href=\"../doc/cw_core/index.html#modules\">api</a>\n\
                     <a href=\"../elsewhere/x.html\">out</a> <a href=\"https://x.org/\">web</a>\n\
                     <!-- <a href=\"commented.html\"> --> <a href=\"/abs.html\">abs</a>\n\
                     <img src=\"view/\"> <a href=\"os.html?x=1&amp;y=2#the%2Dkernel\">q</a>\n";
        let files = Memory::new(&[
            ("/t/book/intro.html", Some(intro)),
            (
                "/t/book/os.html",
                Some("<h2 id=\"the-kernel\">The kernel</h2>"),
            ),
            ("/t/book/css/a.css", Some("")),
            ("/t/book/book.js", Some("")),
            ("/t/book/view/index.html", Some("")),
            ("/t/doc/cw_core/index.html", Some("<h2 id=\"modules\">")),
        ]);
        let mut anchors = Anchors::new(&files);
        let (book, api) = (Path::new("/t/book"), Path::new("/t/doc"));
        let (broken, checked) = check_html(
            Path::new("/t/book/intro.html"),
            intro,
            &[(book, "the book"), (api, "the API docs")],
            None,
            &mut anchors,
        );
        let found: Vec<(usize, &str)> =
            broken.iter().map(|b| (b.line, b.target.as_str())).collect();
        assert_eq!(
            found,
            [
                (4, "os.html#nope"),
                (5, "#outro"),
                (5, "gone.html"),
                (7, "../elsewhere/x.html"),
                (8, "/abs.html"),
            ]
        );
        assert_eq!(checked, 12);

        // From a crate page: links within the API docs are rustdoc's; those leaving them
        // must land in the book.
        let page = "<a href=\"../../book/os.html#the-kernel\">ok</a>\
                    <a href=\"../../book/os.html#kernel\">bad</a>\
                    <a href=\"struct.X.html\">rustdoc's</a><a href=\"../../README.md\">out</a>";
        let (broken, checked) = check_html(
            Path::new("/t/doc/cw_core/index.html"),
            page,
            &[(book, "the book")],
            Some(api),
            &mut anchors,
        );
        let found: Vec<&str> = broken.iter().map(|b| b.target.as_str()).collect();
        assert_eq!(found, ["../../book/os.html#kernel", "../../README.md"]);
        assert_eq!(checked, 3);
    }

    #[test]
    fn ids_are_every_id_and_the_names_of_anchors() {
        let html = "<h1 id=\"a\">x</h1><a name=\"b\"></a><meta name=\"c\"><p data-id=\"d\" ID='e'>";
        assert_eq!(html_ids(html), ["a", "b", "e"].map(String::from).into());
    }

    fn example(line: usize, command: &str, status: Status, output: &str) -> Example {
        Example {
            line,
            command: command.into(),
            status,
            output: output.into(),
        }
    }

    #[test]
    fn a_transcript_has_commands_statuses_and_outputs() {
        let text = "# Title\n\n```console\n$ echo one\none\n$ false\n? 1\n$ cargo run \\\n    \
                    --release -- --x \\\n    y\n? failed\nerror[..]\n...\n\n$ true\n```\n\n\
                    ```sh\n$ not a transcript\n```\n\n  ```console\n  $ ls\n  a\n  ```\n";
        let blocks = transcripts(text).expect("well formed");
        assert_eq!(
            blocks,
            [
                vec![
                    example(4, "echo one", Status::Code(0), "one"),
                    example(6, "false", Status::Code(1), ""),
                    example(
                        8,
                        "cargo run \\\n    --release -- --x \\\n    y",
                        Status::Failed,
                        "error[..]\n...\n"
                    ),
                    example(15, "true", Status::Code(0), ""),
                ],
                vec![example(23, "ls", Status::Code(0), "a")],
            ]
        );
        assert_eq!(
            one_line("cargo run \\\n    --release -- --x \\\n    y"),
            "cargo run --release -- --x y"
        );
    }

    #[test]
    fn a_malformed_transcript_is_refused_with_its_lines() {
        let text = "```console\noutput first\n$ a\n? maybe\n$ b \\\n```\n\n```console\n$\n```\n";
        let errors: Vec<usize> = transcripts(text)
            .expect_err("malformed")
            .into_iter()
            .map(|(line, _)| line)
            .collect();
        assert_eq!(errors, [2, 4, 5, 9]);
        assert_eq!(parse_status("255"), Some(Status::Code(255)));
        assert_eq!(parse_status("256"), None);
        assert_eq!(parse_status("-1"), None);
    }

    /// Any text at all, as a Markdown page, an HTML page or a transcript: every reader
    /// returns (links, anchors, ids, examples or errors naming lines) and none panics,
    /// whatever the bytes (multi-byte characters next to the markup the readers look for,
    /// unclosed fences, brackets and tags, lines of `$ ` and `? `).
    #[test]
    fn any_text_is_read_without_a_panic() {
        bolero::check!()
            .with_type::<String>()
            .for_each(|text: &String| {
                let _ = markdown_links(text);
                let _ = heading_anchors(text);
                let _ = html_links(text);
                let _ = html_ids(text);
                if let Err(errors) = transcripts(text) {
                    assert!(!errors.is_empty(), "an error without a line");
                }
                let _ = prose(text);
            });
    }

    /// The same over text made of the markup the readers act on, so that random input
    /// reaches their deeper states (fences inside lists, links with titles and angle
    /// brackets, code spans of any length, tags with attributes, headings of every form).
    #[test]
    fn markup_soup_is_read_without_a_panic() {
        const PIECES: &[&str] = &[
            "```",
            "````",
            "~~~",
            "console",
            "\n",
            "    ",
            "- ",
            "> ",
            "# ",
            "## ",
            "===",
            "---",
            "[",
            "]",
            "(",
            ")",
            "<",
            ">",
            "![",
            "](",
            "\"",
            "'",
            "`",
            "``",
            "\\",
            "#",
            "a.md",
            "../x",
            "é",
            "中",
            "🦀",
            "$ ",
            "? ",
            "? 2",
            "? failed",
            " \\",
            "...",
            "[..]",
            "<a href=\"",
            "<img src='",
            "id=\"",
            "&amp;",
            "&#x41;",
            "<!--",
            "-->",
            "*",
            "_",
            "{#id}",
            " ",
            "x",
        ];
        bolero::check!()
            .with_type::<Vec<u8>>()
            .for_each(|picks: &Vec<u8>| {
                let text: String = picks
                    .iter()
                    .map(|&p| PIECES[usize::from(p) % PIECES.len()])
                    .collect();
                let _ = markdown_links(&text);
                let _ = heading_anchors(&text);
                let _ = html_links(&text);
                let _ = html_ids(&text);
                let _ = transcripts(&text);
                let _ = prose(&text);
            });
    }

    /// A printed text matches itself shown as it is, when it holds no wildcard (no
    /// `[..]`, no line that is `...`); `...` alone matches anything printed; and a line
    /// shown with `[..]` in place of any run of its characters matches that line.
    #[test]
    fn wildcards_match_what_they_stand_for() {
        bolero::check!()
            .with_type::<(String, String, String)>()
            .for_each(|(text, head, tail): &(String, String, String)| {
                assert!(output_matches("...", text));
                let literal =
                    !text.contains("[..]") && !text.lines().any(|l| l.trim_end() == "...");
                if literal {
                    assert!(output_matches(text, text), "{text:?} does not match itself");
                }
                let (head, tail) = (head.replace('\n', " "), tail.replace('\n', " "));
                let line = text.replace('\n', " ");
                if !head.contains("[..]") && !tail.contains("[..]") {
                    let pattern = format!("{head}[..]{tail}");
                    assert!(
                        line_matches(&pattern, &format!("{head}{line}{tail}")),
                        "{pattern:?} does not match its own expansion"
                    );
                }
            });
    }

    #[test]
    fn output_matches_literally_ignoring_trailing_whitespace_and_lines() {
        assert!(output_matches("a\nb", "a  \nb\n\n\n"));
        assert!(output_matches("a\nb\n\n", "a\nb"));
        assert!(output_matches("", ""));
        assert!(output_matches("", "\n  \n"));
        assert!(!output_matches("a", "a\nb"));
        assert!(!output_matches("a\nb", "a"));
        assert!(!output_matches("", "a"));
        assert!(!output_matches(" a", "a"));
        assert!(!output_matches("a\n\nb", "a\nb"));
    }

    #[test]
    fn dots_match_any_number_of_whole_lines() {
        // At the start, in the middle, at the end; none at all.
        assert!(output_matches("...\nlast", "1\n2\nlast"));
        assert!(output_matches("...\nlast", "last"));
        assert!(output_matches("first\n...\nlast", "first\n1\n2\nlast"));
        assert!(output_matches("first\n...\nlast", "first\nlast"));
        assert!(output_matches("first\n...", "first\n1\n2"));
        assert!(output_matches("first\n...", "first"));
        assert!(output_matches("...", ""));
        assert!(output_matches("...", "a\nb"));
        assert!(output_matches("...\n...", "a"));
        assert!(!output_matches("first\n...", "1\nfirst"));
        assert!(!output_matches("...\nlast", "last\n1"));
        // Backtracking: the first `x` the dots could stop at is not the right one.
        assert!(output_matches("...\nx\ny", "x\nx\ny"));
        assert!(output_matches("a\n...\nx\n...\nx\nz", "a\nx\n1\nx\nx\nz"));
        assert!(!output_matches("a\n...\nx\n...\nx\nz", "a\nx\nz"));
        // `...` within a line is text.
        assert!(output_matches("a ... b", "a ... b"));
        assert!(!output_matches("a ... b", "a 1 b"));
    }

    #[test]
    fn brackets_match_any_run_of_characters_within_a_line() {
        assert!(line_matches("ok ([..] s)", "ok (1.2 s)"));
        assert!(line_matches("ok ([..] s)", "ok ( s)"));
        assert!(line_matches("[..]", ""));
        assert!(line_matches("[..]", "anything"));
        assert!(line_matches("[..]end", "the end"));
        assert!(line_matches("start[..]", "start here"));
        assert!(line_matches("[..] of [..] in [..] s", "3 of 4 in 0.2 s"));
        assert!(line_matches("a[..]b[..]c", "abbcbc"));
        assert!(line_matches("a[..][..]b", "ab"));
        // Backtracking: the last part must end the line, not its first place.
        assert!(line_matches("x[..]ab", "xabab"));
        assert!(line_matches("a[..]a", "aa"));
        assert!(!line_matches("a[..]a", "a"));
        assert!(!line_matches("a[..]b", "a\u{20}c"));
        assert!(!line_matches("a[..]b[..]c", "acb"));
        assert!(!line_matches("start[..]", "star"));
        // Only whole lines: `[..]` does not take a line end.
        assert!(!output_matches("a[..]b", "a\nb"));
        assert!(output_matches(
            "warning: [..]\n...\nok",
            "warning: x y\nmore\nok"
        ));
    }

    #[test]
    fn a_diff_shows_missing_and_unexpected_lines_around_the_wildcards() {
        let expected = "1\n2\n3\n4\n5\n6\nseven\n...\nend";
        let actual = "1\n2\n3\n4\n5\n6\n7\nx\ny\nend\nextra";
        assert_eq!(
            diff(expected, actual),
            "  (4 line(s) as expected)\n  5\n  6\n- seven\n  7\n  x\n  y\n  end\n+ extra"
        );
    }

    #[test]
    fn paths_are_normalized_by_their_names() {
        assert_eq!(
            normalize(Path::new("/r/docs/../target/./book")),
            Path::new("/r/target/book")
        );
        assert_eq!(normalize(Path::new("/a/../../b")), Path::new("/b"));
        assert_eq!(normalize(Path::new("../../a/../b")), Path::new("../../b"));
    }

    #[test]
    fn targets_with_a_scheme_or_host_are_not_checked() {
        assert_eq!(relative("https://x.org/a"), None);
        assert_eq!(relative("mailto:a@b.c"), None);
        assert_eq!(relative("//cdn.x/a.js"), None);
        assert_eq!(
            relative("a%20b.md?raw=1#sec%2D1"),
            Some(("a b.md".into(), Some("sec-1".into())))
        );
        assert_eq!(relative("#top"), Some((String::new(), Some("top".into()))));
    }

    #[test]
    fn entities_and_escapes_are_resolved() {
        assert_eq!(
            decode_entities("a&amp;b &lt;&#39;&#x41;&unknown; &"),
            "a&b <'A&unknown; &"
        );
        assert_eq!(unescape(r"\(a\)\\b\c"), r"(a)\b\c");
        assert_eq!(percent_decode("%41%zz%"), "A%zz%");
    }
}
