"""The diagnosis's physical effects, one family per module; :mod:`radtree.diagnose.registry`
names each effect's class (adding one: a class in a module here, or a new module, and one
registry line)."""
