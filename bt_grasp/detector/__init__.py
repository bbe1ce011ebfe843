"""Learned oriented-box detection (YOLO-OBB exported to ONNX), decoded by bt_grasp's own numpy code.

``letterbox`` and ``obb`` need only numpy and OpenCV; ``model`` wraps an onnxruntime session and imports
onnxruntime only when a model is loaded (a tree that does not use a learned detector never pays for it).
Ultralytics (AGPL-3.0) is not a dependency of anything here: the pre- and post-processing follow its published
behaviour (LetterBox, ``non_max_suppression(rotated=True)``, ``batch_probiou``, ``regularize_rboxes``,
``scale_boxes(xywh=True)``) and are checked by tests that compute the expected numbers by hand.
"""
