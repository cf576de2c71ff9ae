"""The config folder of my_plugins (hydra.searchpath=[pkg://my_plugins.conf]): Hydra reads a
pkg:// path only from a package, hence this file."""
