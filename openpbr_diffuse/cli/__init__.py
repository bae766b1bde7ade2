"""Command-line interface: ``openpbr-diffuse <command>``; one module per command."""
