//! The project's files at the root agree with its manifests: the licences the manifests name
//! are there, `CITATION.cff` cites the paper and the version being built, `CHANGELOG.md` keeps
//! an Unreleased section.

fn root_file(name: &str) -> String {
    let path = hystcomp_testkit::workspace_root().join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn workspace_value(key: &str) -> String {
    let manifest = root_file("Cargo.toml");
    let line = manifest
        .lines()
        .find(|l| l.starts_with(&format!("{key} = ")))
        .unwrap_or_else(|| panic!("the workspace manifest sets {key}"));
    line.split('"').nth(1).expect("a quoted value").to_owned()
}

#[test]
fn the_licences_the_manifests_name_are_at_the_root() {
    assert_eq!(workspace_value("license"), "MIT OR Apache-2.0");
    let mit = root_file("LICENSE-MIT");
    assert!(mit.starts_with("MIT License"), "LICENSE-MIT");
    assert!(mit.contains("Permission is hereby granted, free of charge"));
    let apache = root_file("LICENSE-APACHE");
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0, January 2004"));
    assert!(
        apache.contains("END OF TERMS AND CONDITIONS"),
        "the whole licence"
    );
    assert!(root_file("README.md").contains("LICENSE-MIT"));
}

#[test]
fn citation_cites_the_paper_and_this_version() {
    let cff = root_file("CITATION.cff");
    assert!(cff.starts_with("# ") && cff.contains("\ncff-version: 1.2.0\n"));
    assert!(cff.contains("\ntype: software\n"));
    assert!(cff.contains("doi: 10.1088/0964-1726/23/9/095029"));
    assert!(cff.contains("family-names: Gu") && cff.contains("family-names: Zhu"));
    let version = cff
        .lines()
        .find_map(|l| l.strip_prefix("version: "))
        .expect("CITATION.cff has a version");
    assert_eq!(version, env!("CARGO_PKG_VERSION"), "CITATION.cff's version");
    // CFF lists an "A OR B" licence choice as a list of SPDX identifiers.
    let listed: String = workspace_value("license")
        .split(" OR ")
        .map(|id| format!("\n  - {id}"))
        .collect();
    assert!(cff.contains(&format!("\nlicense:{listed}\n")), "{listed}");
    assert!(cff.contains(&format!(
        "repository-code: \"{}\"",
        workspace_value("repository")
    )));
    // Plain YAML: no tabs, which YAML forbids for indentation. (`cffconvert --validate`
    // accepted this file; it is not run here, to keep CI off the package index.)
    assert!(!cff.contains('\t'));
}

#[test]
fn changelog_keeps_an_unreleased_section_and_names_this_version() {
    let log = root_file("CHANGELOG.md");
    let unreleased = log.find("\n## [Unreleased]\n").expect("## [Unreleased]");
    let this = log
        .find(&format!("\n## [{}]", env!("CARGO_PKG_VERSION")))
        .expect("a section for the manifests' version");
    assert!(unreleased < this, "Unreleased comes first");
}
