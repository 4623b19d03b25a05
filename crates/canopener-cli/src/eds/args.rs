//! Options of the `eds` commands.

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};

use crate::grammar::{parse_cia_bitrate, parse_index, parse_node_id};

#[derive(Debug, Subcommand)]
pub(crate) enum EdsCommand {
    /// Show the object dictionary of an EDS, DCF, XDD/XDC or canopener JSON file as a table.
    #[command(after_help = "Examples:
  canopener eds show device.eds
  canopener eds show device.eds --object 1018        # one object (0x1018, 1018h and 1018 all mean 1018h)
  canopener eds show device.eds --node-id 5          # also resolve $NODEID formulas for node 5
  canopener eds show device.xdd --format json | jq '.objects[] | select(.pdo_mapping)'")]
    Show(EdsShowArgs),
    /// Convert between EDS, DCF, XDD/XDC and canopener's JSON form.
    #[command(after_help = "Examples:
  canopener eds convert device.eds --to json -o device.json
  canopener eds convert device.eds --to dcf --node-id 5 --bitrate 250 -o node5.dcf
  canopener eds convert node5.dcf --to eds                # drop the DCF additions, print to stdout
  canopener eds convert device.eds --to xdd -o device.xdd # CiA 311 v1.1 (an XDC when the input is a DCF)
  canopener eds convert device.xdd --to eds -o device.eds")]
    Convert(EdsConvertArgs),
    /// Rewrite a file as canonical CiA 306 text (section order, key spelling, CR/LF; values and comments kept).
    #[command(after_help = "Examples:
  canopener eds fmt device.eds                   # canonical text on stdout
  canopener eds fmt device.eds -o clean.eds
  canopener eds fmt device.eds --in-place        # keeps device.eds.bak
  canopener eds fmt device.eds --check           # exit 1 if the file is not canonical")]
    Fmt(EdsFmtArgs),
    /// Semantic difference of two EDS/DCF/XDD files: objects and attributes added, removed or changed.
    #[command(after_help = "Examples:
  canopener eds diff firmware-1.2.eds firmware-1.3.eds
  canopener eds diff vendor.eds vendor.xdd             # formats may differ; notation and layout do not count
  canopener eds diff a.eds b.eds --format json | jq '.changes[] | select(.significant)'
Exit status: 0 same device and object dictionary ([FileInfo] metadata may differ), 1 different, 2 trouble.")]
    Diff(EdsDiffArgs),
    /// Check EDS/DCF and CiA 311 XDD/XDC/XPD files against CiA 306/311/301, reference profiles, tool portability and rule packs.
    #[command(after_help = "Examples:
  canopener eds check device.eds
  canopener eds check device.xdd                  # XML is recognised by its content; findings point into the XML
  canopener eds check vendor/ 'more/*.dcf' --format sarif -o eds.sarif   # directories and globs, in parallel
  canopener eds check device.eds --deny warnings                  # CI: warnings fail too
  canopener eds check device.eds --rules project.toml --tag naming   # your own rules, only one tag
  canopener eds check device.eds --skip T001,T004 --format json | jq '.summary'
  canopener eds check vendor/ --format html -o report.html        # one self-contained page
Exit status: 0 no errors, 1 errors found (or warnings with --deny warnings), 2 a file could not be read,
or bad arguments.")]
    Check(EdsCheckArgs),
    /// Print the explanation of a check: what it verifies, why, the specification clause, how to fix it.
    #[command(after_help = "Examples:
  canopener eds explain C301
  canopener eds explain sub-number-mismatch          # slugs work too
  canopener eds explain paper/no-blank-names --rules seed-paper.toml")]
    Explain(EdsExplainArgs),
    /// List checks: built-in and from rule packs.
    #[command(subcommand)]
    Rules(EdsRulesCommand),
    /// Apply the safe fixes (SubNumber, object lists, sub-index 0, section names, key spelling, rule-pack fixes).
    #[command(after_help = "Examples:
  canopener eds fix device.eds --dry-run             # show a unified diff, write nothing
  canopener eds fix device.eds -o fixed.eds
  canopener eds fix device.eds --in-place            # keeps device.eds.bak
  canopener eds fix device.eds --in-place --only P045,P044
  canopener eds fix device.eds --rules seed-paper.toml --dry-run
Every untouched line stays byte-identical. Fixes that change what the file says about the device
(e.g. a sub-index 0 default) are marked as such. XDD/XDC files are refused (exit 2): fixes are
EDS/DCF text edits. Exit status: 0 no errors remain, 1 errors remain (or warnings with --deny
warnings), 2 trouble.")]
    Fix(EdsFixArgs),
}

/// `eds rules` subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum EdsRulesCommand {
    /// Show every check, built-in and user, with its code, severity, tags and title.
    #[command(after_help = "Examples:
  canopener eds rules list
  canopener eds rules list --tag portability
  canopener eds rules list --rules seed-paper.toml --format json")]
    List(EdsRulesListArgs),
}

/// Which checks run: shared by `eds check`, `eds fix` and `eds rules list`.
#[derive(Debug, Clone, Args)]
pub(crate) struct CheckSelectionArgs {
    /// A rule pack (TOML, see crates/canopener-rules/README.md); repeatable.
    #[arg(long = "rules", value_name = "PACK")]
    pub(crate) rules: Vec<PathBuf>,
    /// Only these checks (codes, slugs or rule ids, comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "CODES")]
    pub(crate) only: Vec<String>,
    /// Never these checks (codes, slugs or rule ids, comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "CODES")]
    pub(crate) skip: Vec<String>,
    /// Only checks with this tag (built-ins are tagged with their group, e.g. cia301, portability); repeatable.
    #[arg(long, value_name = "TAG")]
    pub(crate) tag: Vec<String>,
}

/// What `eds check` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum CheckFormat {
    /// Compiler-style diagnostics with the source line, a caret and help.
    Human,
    /// One JSON document (docs/check-json.md).
    Json,
    /// SARIF 2.1.0 for GitHub/GitLab code scanning.
    Sarif,
    /// JUnit XML: one test case per check per file.
    Junit,
    /// One self-contained HTML page with filters and explanations.
    Html,
}

/// What else fails `eds check` besides errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum DenyLevel {
    /// Warnings fail too.
    Warnings,
}

/// When to color human output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ColorChoice {
    /// When writing to a terminal and NO_COLOR is not set.
    Auto,
    /// Always.
    Always,
    /// Never.
    Never,
}

#[derive(Debug, Args)]
pub(crate) struct EdsCheckArgs {
    /// Files, directories (every .eds/.dcf below) or glob patterns.
    #[arg(required = true, value_name = "FILE|DIR|GLOB")]
    pub(crate) inputs: Vec<String>,
    #[command(flatten)]
    pub(crate) selection: CheckSelectionArgs,
    #[arg(long, value_enum, default_value_t = CheckFormat::Human)]
    pub(crate) format: CheckFormat,
    /// Write the report here (atomically) instead of stdout.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Fail (exit 1) on warnings too.
    #[arg(long, value_enum, value_name = "LEVEL")]
    pub(crate) deny: Option<DenyLevel>,
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto)]
    pub(crate) color: ColorChoice,
    /// No per-code summary table at the end of human output.
    #[arg(long)]
    pub(crate) no_summary: bool,
}

#[derive(Debug, Args)]
pub(crate) struct EdsExplainArgs {
    /// A code (C301, P020, T004), a slug (sub-number-mismatch) or a rule id from --rules.
    pub(crate) code: String,
    /// A rule pack whose rules can be explained too; repeatable.
    #[arg(long = "rules", value_name = "PACK")]
    pub(crate) rules: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

#[derive(Debug, Args)]
pub(crate) struct EdsRulesListArgs {
    #[command(flatten)]
    pub(crate) selection: CheckSelectionArgs,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

#[derive(Debug, Args)]
pub(crate) struct EdsFixArgs {
    /// The EDS or DCF file.
    pub(crate) file: PathBuf,
    /// Write the fixed file here (atomically) instead of stdout; never the input file.
    #[arg(short, long, value_name = "OUT", conflicts_with = "in_place")]
    pub(crate) output: Option<PathBuf>,
    /// Rewrite the input file, keeping FILE.bak.
    #[arg(long)]
    pub(crate) in_place: bool,
    /// Print a unified diff of the fixes and write nothing.
    #[arg(long)]
    pub(crate) dry_run: bool,
    #[command(flatten)]
    pub(crate) selection: CheckSelectionArgs,
    /// Exit 1 when warnings remain too.
    #[arg(long, value_enum, value_name = "LEVEL")]
    pub(crate) deny: Option<DenyLevel>,
}

/// How `eds` commands report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ReportFormat {
    /// Text for people.
    Human,
    /// One JSON document for machines.
    Json,
}

/// What `eds convert` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ConvertTarget {
    /// canopener's versioned JSON form of the model (docs/eds-json.md).
    Json,
    /// A CiA 306 EDS (from a DCF/XDC: the DCF additions removed, each named on stderr).
    Eds,
    /// A CiA 306 DCF for one node: from an EDS/XDD, every value filled from its default (needs --node-id
    /// and --bitrate); from a DCF/XDC, its values exactly as they are (--node-id/--bitrate replace its own).
    Dcf,
    /// A CiA 311 v1.1 XDD, or an XDC when the input is a DCF.
    Xdd,
}

#[derive(Debug, Args)]
pub(crate) struct EdsShowArgs {
    /// The file: EDS, DCF, XDD, XDC or canopener JSON.
    pub(crate) file: PathBuf,
    /// Show only this object (hexadecimal: 1018, 0x1018 or 1018h).
    #[arg(long, value_parser = parse_index, value_name = "INDEX")]
    pub(crate) object: Option<u16>,
    /// Resolve $NODEID formulas for this node-ID (a DCF's own node-ID is used by default).
    #[arg(long, value_parser = parse_node_id, value_name = "N")]
    pub(crate) node_id: Option<u8>,
    /// List every loading diagnostic, not just the summary.
    #[arg(long)]
    pub(crate) diagnostics: bool,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

#[derive(Debug, Args)]
pub(crate) struct EdsConvertArgs {
    /// The file: EDS, DCF, XDD, XDC or canopener JSON.
    pub(crate) file: PathBuf,
    /// The format to write.
    #[arg(long, value_enum)]
    pub(crate) to: ConvertTarget,
    /// Write here (atomically) instead of stdout; never the input file.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Node-ID of the DCF (1..127).
    #[arg(long, value_parser = |t: &str| parse_node_id(t).map(u16::from), value_name = "N")]
    pub(crate) node_id: Option<u16>,
    /// Bit rate of the DCF in kbit/s (10, 20, 50, 125, 250, 500, 800, 1000).
    #[arg(long, value_name = "KBIT", value_parser = parse_cia_bitrate)]
    pub(crate) bitrate: Option<u16>,
    /// List every loading diagnostic, not just the summary.
    #[arg(long)]
    pub(crate) diagnostics: bool,
}

#[derive(Debug, Args)]
pub(crate) struct EdsFmtArgs {
    /// The EDS or DCF file.
    pub(crate) file: PathBuf,
    /// Write here (atomically) instead of stdout.
    #[arg(short, long, value_name = "OUT", conflicts_with_all = ["in_place", "check"])]
    pub(crate) output: Option<PathBuf>,
    /// Replace the file itself, keeping the original as FILE.bak.
    #[arg(long, conflicts_with = "check")]
    pub(crate) in_place: bool,
    /// Write nothing; exit 1 if the file is not in canonical form.
    #[arg(long)]
    pub(crate) check: bool,
    /// List every loading diagnostic, not just the summary.
    #[arg(long)]
    pub(crate) diagnostics: bool,
}

#[derive(Debug, Args)]
pub(crate) struct EdsDiffArgs {
    /// The first (old) file.
    pub(crate) a: PathBuf,
    /// The second (new) file.
    pub(crate) b: PathBuf,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}
