"""mkdocs hooks (mkdocs.yml `hooks:`): pages generated from the code at build time, so that they
cannot drift from it. `cli.md`: every command's `--help`, from the commands themselves;
`changelog.md`: the repository's CHANGELOG.md."""

from pathlib import Path

import click

ROOT = Path(__file__).resolve().parents[1]
MARKER = "<!-- generated -->"


def cli_reference() -> str:
    import typer

    from jaxrock.cli import app

    group = typer.main.get_command(app)
    root = click.Context(group, info_name="jaxrock", max_content_width=100, terminal_width=100)
    parts = ["```text", group.get_help(root), "```"]
    for name in group.list_commands(root):
        command = group.get_command(root, name)
        ctx = click.Context(command, info_name=name, parent=root, max_content_width=100, terminal_width=100)
        parts += [f"## jaxrock {name}", "", "```text", command.get_help(ctx), "```", ""]
    return "\n".join(parts)


def on_page_markdown(markdown, page, config, files):
    if MARKER not in markdown:
        return markdown
    if page.file.src_uri == "cli.md":
        return markdown.replace(MARKER, cli_reference())
    if page.file.src_uri == "changelog.md":
        return markdown.replace(MARKER, (ROOT / "CHANGELOG.md").read_text(encoding="utf-8").split("\n", 1)[1])
    return markdown
