"""Tree file formats: BT.CPP v4 XML, its YAML twin, the format-neutral :class:`Document` both produce, and
conversion between them."""
