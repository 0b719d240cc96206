from mtident.cli import thermal  # noqa: F401
