"""The trust boundary: every byte bt_grasp reads from a user's files and every file it writes where a user says.

One package that a security review can read alone (``docs/security.md``):

- ``bounded_io``: the one bounded reader (regular files only, a size limit per kind);
- ``bounded_yaml``: YAML parsed with bounds (no tags, no alias bombs);
- ``config``: strict loading of the YAML files users write into frozen, validated models;
- ``safe_path``: the one gate through which a name read from a file becomes a path;
- ``search_path``: where a name a user's own file gives (an include, a scene's calibration) is looked for;
- ``output_files``: the one gate for every file and folder written where a user says;
- ``terminal_text``: text from files and peers made safe to print;
- ``image_header``: a picture's size read from its header before anything is decoded.

Every module here imports only ``bt_grasp.errors`` and this package (``tests/test_architecture.py``).
"""
