//! The two sides of an A/B: a tetbench binary given by path, or a git revision built in a git
//! worktree and cached by commit, so that `bisect` and repeated `ab`s build each commit once.
//!
//! One worktree and one cargo target directory per cache (not per commit): a commit checked out
//! over the previous one rebuilds only the crates that changed, while a fresh target per commit
//! would recompile every dependency (15–30 minutes on the shared 2-core VM). A file lock
//! serialises builds into one cache; each built binary is copied out to `bin/COMMIT/`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::results::write_file;
use anyhow::Context;

/// How revisions are built (`--build-*` of `ab` and `bisect`).
#[derive(Debug, Clone, clap::Args)]
pub struct BuildArgs {
    /// Where built revisions are kept (worktree, cargo target, binaries per commit); default:
    /// the reference cache's `ab-builds` ($TETBENCH_CACHE, else ~/.cache/tetbench).
    #[arg(long, value_name = "DIR")]
    pub build_cache: Option<PathBuf>,
    /// Shell command that builds a revision, run in its worktree with CARGO_TARGET_DIR set to
    /// the cache's target directory.
    #[arg(
        long,
        default_value = "cargo build --release -p harness --bin tetbench"
    )]
    pub build_command: String,
    /// The binary the build command leaves: `{target}` is the cache's target directory, a
    /// relative path is inside the worktree.
    #[arg(long, default_value = "{target}/release/tetbench")]
    pub build_output: String,
    /// The git repository revisions are taken from (default: the current directory's).
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub repo: PathBuf,
}

impl BuildArgs {
    pub fn cache(&self) -> PathBuf {
        self.build_cache.clone().unwrap_or_else(|| {
            crate::run::plan::default_cache_dir(Path::new(".")).join("ab-builds")
        })
    }
}

/// One side, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct Binary {
    /// What the user named (a path or a revision).
    pub spec: String,
    pub path: PathBuf,
    /// The commit it was built from, when it was named by revision.
    pub commit: Option<String>,
}

impl Binary {
    /// `abc1234def (HEAD~2)` or the path.
    pub fn label(&self) -> String {
        match &self.commit {
            Some(c) if *c != self.spec => format!("{} ({})", &c[..c.len().min(10)], self.spec),
            Some(c) => c[..c.len().min(10)].to_string(),
            None => self.path.display().to_string(),
        }
    }
}

/// Runs git in `dir`; stdout trimmed, or an error with git's message.
pub fn git(dir: &Path, args: &[&str]) -> anyhow::Result<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .with_context(|| format!("cannot run git in {}", dir.display()))?;
    anyhow::ensure!(
        out.status.success(),
        "git {} in {}: {}",
        args.join(" "),
        dir.display(),
        String::from_utf8_lossy(&out.stderr).trim()
    );
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The full commit a revision names in `repo`.
pub fn commit_of(repo: &Path, rev: &str) -> anyhow::Result<String> {
    git(
        repo,
        &[
            "rev-parse",
            "--verify",
            "--quiet",
            &format!("{rev}^{{commit}}"),
        ],
    )
    .with_context(|| {
        format!(
            "{rev} is not a commit of the git repository {}",
            repo.display()
        )
    })
}

/// A side named by `spec`: an existing file is a binary as it is, anything else a revision to
/// build.
pub fn resolve(spec: &str, args: &BuildArgs) -> anyhow::Result<Binary> {
    let p = Path::new(spec);
    if p.is_file() {
        return Ok(Binary {
            spec: spec.to_string(),
            path: std::path::absolute(p)
                .with_context(|| format!("cannot resolve the path {spec}"))?,
            commit: None,
        });
    }
    let commit = commit_of(&args.repo, spec).with_context(|| {
        format!("{spec} is neither a tetbench binary (no such file) nor a git revision")
    })?;
    let path = build_commit(&commit, args)?;
    Ok(Binary {
        spec: spec.to_string(),
        path,
        commit: Some(commit),
    })
}

/// The cache's worktree of the repository at `commit` (added on first use, else checked out
/// and cleaned): one per repository, whichever checkout of it asks.
fn checkout(cache: &Path, commit: &str, repo: &Path) -> anyhow::Result<PathBuf> {
    let repo = std::path::absolute(repo)?;
    let common = git(
        &repo,
        &["rev-parse", "--path-format=absolute", "--git-common-dir"],
    )?;
    let tree = cache.join(format!(
        "src-{:016x}",
        crate::results::names::stable_hash(&common)
    ));
    if tree.join(".git").exists() {
        git(
            &tree,
            &["checkout", "--quiet", "--force", "--detach", commit],
        )?;
        git(&tree, &["clean", "--quiet", "-fd"])?;
    } else {
        git(&repo, &["worktree", "prune"])?;
        git(
            &repo,
            &[
                "worktree",
                "add",
                "--quiet",
                "--detach",
                &tree.display().to_string(),
                commit,
            ],
        )?;
    }
    Ok(tree)
}

/// Builds `commit` (or finds it built before) and returns the binary's path in the cache.
pub fn build_commit(commit: &str, args: &BuildArgs) -> anyhow::Result<PathBuf> {
    let cache = std::path::absolute(args.cache()).context("cannot resolve the build cache")?;
    let recipe = format!("{}\n{}\n", args.build_command, args.build_output);
    let bin_dir = cache.join("bin").join(commit);
    let name = Path::new(&args.build_output)
        .file_name()
        .with_context(|| format!("--build-output {} names no file", args.build_output))?
        .to_owned();
    let bin = bin_dir.join(&name);
    let recipe_file = bin_dir.join("build-recipe.txt");
    let built =
        || bin.is_file() && std::fs::read_to_string(&recipe_file).ok().as_deref() == Some(&recipe);
    if built() {
        eprintln!(
            "tetbench: {} already built ({})",
            &commit[..12.min(commit.len())],
            bin.display()
        );
        return Ok(bin);
    }
    std::fs::create_dir_all(&cache)
        .with_context(|| format!("cannot create {}", cache.display()))?;
    // One build at a time per cache: they share the worktree and the target directory.
    let lock_path = cache.join(".build.lock");
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock_path)
        .with_context(|| format!("cannot open {}", lock_path.display()))?;
    fs4::FileExt::lock(&lock).with_context(|| format!("cannot lock {}", lock_path.display()))?;
    if built() {
        return Ok(bin);
    }
    let tree = checkout(&cache, commit, &args.repo)?;
    let target = cache.join("target");
    eprintln!(
        "tetbench: building {} in {} ({})",
        &commit[..12.min(commit.len())],
        tree.display(),
        args.build_command
    );
    let status = Command::new("sh")
        .arg("-c")
        .arg(&args.build_command)
        .current_dir(&tree)
        .env("CARGO_TARGET_DIR", &target)
        .stdout(std::process::Stdio::inherit())
        .stderr(std::process::Stdio::inherit())
        .status()
        .with_context(|| format!("cannot run the build command in {}", tree.display()))?;
    anyhow::ensure!(
        status.success(),
        "building {commit} failed ({status}): `{}` in {}",
        args.build_command,
        tree.display()
    );
    let output = args
        .build_output
        .replace("{target}", &target.display().to_string());
    let output = tree.join(output);
    anyhow::ensure!(
        output.is_file(),
        "building {commit} left no {} (--build-output)",
        output.display()
    );
    std::fs::create_dir_all(&bin_dir)
        .with_context(|| format!("cannot create {}", bin_dir.display()))?;
    std::fs::copy(&output, &bin)
        .with_context(|| format!("cannot copy {} to {}", output.display(), bin.display()))?;
    write_file(&recipe_file, recipe)?;
    Ok(bin)
}
