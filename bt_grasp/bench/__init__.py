"""Developer benchmarks: measurements of bt_grasp itself (``bt-grasp bench ...``), and their simulator backends.

The one package besides ``sim/`` and the judge that may read ground truth (``bt_grasp.sim.oracle``): a
benchmark scores the pipeline against the simulator's truth, which the pipeline itself never reads
(``tests/test_architecture.py`` enforces it as a folder rule). Nothing in the product imports this package;
``cli/`` calls it. To evaluate a tree, users run campaigns (``bt_grasp.campaign``), not benchmarks.
"""
