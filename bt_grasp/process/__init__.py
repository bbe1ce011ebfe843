"""Process set-up: what a bt_grasp process does once, before and around its work.

- ``numeric_threads``: one OpenBLAS thread per process, set before numpy is imported;
- ``slim_imports``: third-party submodules bt_grasp never uses, loaded only if touched;
- ``environment``: the machine and library strings a run or benchmark records;
- ``code_fingerprint``: one digest of the code and libraries a process runs.
"""
