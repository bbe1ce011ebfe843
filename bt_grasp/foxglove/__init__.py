"""foxglove"""
