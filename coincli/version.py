"""The package version (stored in every store and recording), and where its documentation is."""

__version__ = "0.11.0"

# The documentation site's address once it is published (mkdocs.yml's site_url): messages then
# link its pages; until then they name them. Never a path under docs/, which a package
# installed with pip lacks.
DOCS_URL: str | None = None


def documentation(page: str, title: str) -> str:
    """Where a message sends the reader for more: the documentation site's page ``page`` (its
    file under docs/ without .md), named ``title`` in the site's menu: its address under
    :data:`DOCS_URL`, or, while there is none, the page by its name."""
    if DOCS_URL:
        return f"{DOCS_URL.rstrip('/')}/{page}/"
    return f'the documentation site\'s page "{title}"'
