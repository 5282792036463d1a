//! The README's table of what to expect is `docs/expect.md`, which
//! `scripts/expect.sh` writes from one `pbgi report` per scene: the block
//! between its markers must be that file, and the file must have measured
//! the Cornell box's current default image (its digest in
//! `docs/image-digests.txt`). A change to the default render makes the
//! table stale until `scripts/expect.sh` runs again.

use std::path::Path;

fn read(path: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

const BEGIN: &str = "<!-- begin docs/expect.md -->\n";
const END: &str = "<!-- end docs/expect.md -->";

/// The text between `README.md`'s markers.
fn block(readme: &str) -> &str {
    let i = readme
        .find(BEGIN)
        .expect("README.md has the table's begin marker")
        + BEGIN.len();
    let j = readme.find(END).expect("README.md has the table's end marker");
    assert!(i <= j, "README.md's table markers are out of order");
    &readme[i..j]
}

#[test]
fn the_readmes_table_is_docs_expect_md() {
    let (readme, table) = (read("README.md"), read("docs/expect.md"));
    assert_eq!(
        block(&readme),
        table,
        "README.md's block differs from docs/expect.md: run scripts/expect.sh (or copy the file in)"
    );
    assert!(
        table.lines().filter(|l| l.starts_with("| ")).count() >= 3,
        "the table has rows"
    );
}

#[test]
fn the_table_measured_the_current_default_image() {
    let table = read("docs/expect.md");
    let digests = read("docs/image-digests.txt");
    let current = digests
        .lines()
        .find_map(|l| l.strip_suffix("  cornell-box"))
        .expect("docs/image-digests.txt has the Cornell box's default digest");
    let measured = table
        .split("image digest ")
        .nth(1)
        .and_then(|rest| rest.get(..16))
        .expect("docs/expect.md names the digest of the image it measured");
    assert_eq!(
        measured, current,
        "docs/expect.md measured another default Cornell box than the current one: run scripts/expect.sh"
    );
}
