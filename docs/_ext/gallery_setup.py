"""Matplotlib settings for the gallery, applied before each example runs.

sphinx-gallery resets matplotlib to its defaults before every example
(``reset_modules``); this runs after that reset.
"""


def reset_matplotlib(gallery_conf, fname):
    """Embedded animations: JPEG frames (a quarter of PNG's size for these
    3-D scenes), so a page with a 40-frame animation stays near 1.5 MB."""
    import matplotlib

    matplotlib.rcParams["animation.frame_format"] = "jpeg"
    matplotlib.rcParams["animation.embed_limit"] = 30.0  # MB
