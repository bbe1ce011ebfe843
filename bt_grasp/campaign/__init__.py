"""Evaluation campaigns: many seeded episodes on warm worker processes or Ray actors, results, reports.

``spec`` loads campaign files, ``worker`` runs episodes on a warm simulator, ``local`` and ``ray_engine``
spread them over processes or a Ray cluster, ``results`` is the durable JSON-lines record, ``report`` draws it.
"""
