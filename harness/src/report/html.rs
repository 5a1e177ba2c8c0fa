//! Every HTML page tetbench writes comes from one minijinja environment. Its templates
//! (`harness/templates/*.html`, and `*.svg` for charts with tooltips, compiled in) escape every
//! value by default — minijinja turns auto-escaping on for names ending in `.html`, and this
//! environment for `.svg` — so a data set, file name, setting or error
//! message that contains markup lands in a page as text, never as a live tag. Pages pass plain
//! serialisable data; no page builds HTML text in Rust.

use std::sync::OnceLock;

use anyhow::Context;
use serde::Serialize;

/// The templates, by name, as `{% extends %}` and `{% include %}` find them.
const TEMPLATES: &[(&str, &str)] = &[
    ("base.html", include_str!("../../templates/base.html")),
    ("charts.html", include_str!("../../templates/charts.html")),
    ("report.html", include_str!("../../templates/report.html")),
    ("history.html", include_str!("../../templates/history.html")),
    (
        "history_chart.svg",
        include_str!("../../templates/history_chart.svg"),
    ),
    ("compare.html", include_str!("../../templates/compare.html")),
    ("site.html", include_str!("../../templates/site.html")),
    (
        "run_brief.html",
        include_str!("../../templates/run_brief.html"),
    ),
    (
        "markdown.html",
        include_str!("../../templates/markdown.html"),
    ),
];

fn environment() -> &'static minijinja::Environment<'static> {
    static ENV: OnceLock<minijinja::Environment<'static>> = OnceLock::new();
    ENV.get_or_init(|| {
        let mut env = minijinja::Environment::new();
        // Undefined values are template bugs: fail the page instead of printing nothing.
        env.set_undefined_behavior(minijinja::UndefinedBehavior::Strict);
        env.set_formatter(escape_markup);
        // SVG is XML: its templates escape as the HTML ones do.
        env.set_auto_escape_callback(|name| {
            if name.ends_with(".svg") {
                minijinja::AutoEscape::Html
            } else {
                minijinja::default_auto_escape_callback(name)
            }
        });
        for (name, source) in TEMPLATES {
            env.add_template(name, source)
                .unwrap_or_else(|e| panic!("template {name} does not compile: {e:#}"));
        }
        env
    })
}

/// minijinja's own HTML escaping also writes '/' as `&#x2f;`, which turns every path and URL
/// in a page into entities; a slash cannot start markup in text or in a quoted attribute, so
/// only `& < > " '` are escaped here, as in Python's `html.escape`.
fn escape_markup(
    out: &mut minijinja::Output,
    state: &mut minijinja::State,
    value: &minijinja::Value,
) -> Result<(), minijinja::Error> {
    if *state.auto_escape() != minijinja::AutoEscape::Html || value.is_safe() {
        return minijinja::escape_formatter(out, state, value);
    }
    let text = value.to_string();
    let mut escaped = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => escaped.push_str("&amp;"),
            '<' => escaped.push_str("&lt;"),
            '>' => escaped.push_str("&gt;"),
            '"' => escaped.push_str("&quot;"),
            '\'' => escaped.push_str("&#x27;"),
            c => escaped.push(c),
        }
    }
    out.write_str(&escaped).map_err(minijinja::Error::from)
}

/// Renders the page `template` with `context`.
pub fn render(template: &str, context: impl Serialize) -> anyhow::Result<String> {
    environment()
        .get_template(template)
        .and_then(|t| t.render(minijinja::Value::from(minijinja::value::Serde(&context))))
        .with_context(|| format!("cannot render the HTML page {template}"))
}

/// The markup every injection test plants in names; see [`assert_no_live_markup`].
pub const HOSTILE_NAME: &str = "<img src=x onerror=alert(1)>";

/// Panics (for tests) when `page` contains [`HOSTILE_NAME`] as markup rather than as text.
pub fn assert_no_live_markup(page: &str) {
    assert!(
        !page.contains("<img src=x") && !page.contains("onerror=alert(1)>"),
        "a name with markup landed in the page as a live tag"
    );
    assert!(
        page.contains("&lt;img src=x onerror=alert(1)&gt;"),
        "the hostile name does not appear escaped in the page at all (was it dropped?)"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_template_compiles() {
        for (name, _) in TEMPLATES {
            environment().get_template(name).unwrap();
        }
    }

    #[test]
    fn values_are_escaped() {
        let env = environment();
        let page = env
            .render_str(
                "{{ name }}",
                minijinja::Value::from(minijinja::value::Serde(
                    serde_json::json!({ "name": HOSTILE_NAME }),
                )),
            )
            .unwrap();
        // render_str has no .html name, so auto-escaping is off: the check must fail here ...
        assert!(std::panic::catch_unwind(|| assert_no_live_markup(&page)).is_err());
    }
}
