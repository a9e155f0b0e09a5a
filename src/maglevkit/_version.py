"""The package version, in a module of its own so any layer may read it without importing the
package ``__init__`` (which sits above every layer)."""

__version__ = "0.1.0"
