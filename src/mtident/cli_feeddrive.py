from mtident.cli import feeddrive  # noqa: F401
