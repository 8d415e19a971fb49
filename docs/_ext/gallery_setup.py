"""Gallery helpers for sphinx-gallery (named in docs/conf.py).

* :func:`reset_matplotlib` runs before each example, after sphinx-gallery's
  own reset of matplotlib to its defaults.
* :func:`orbits_figure_scraper` shows the figures that ``orbits.figures``
  builds.  They have an Agg canvas of their own, not a pyplot manager
  (so that the CLI never opens a window), and the matplotlib scraper only
  sees pyplot figures.
"""

import weakref

_SHOWN = weakref.WeakSet()


def reset_matplotlib(gallery_conf, fname):
    """Embedded animations with JPEG frames (a quarter of PNG's size for these
    3-D scenes): a page with a 40-frame animation stays near 2 MB."""
    import matplotlib

    matplotlib.rcParams["animation.frame_format"] = "jpeg"
    matplotlib.rcParams["animation.embed_limit"] = 30.0  # MB


def orbits_figure_scraper(block, block_vars, gallery_conf):
    """Save the new pyplot-less Figures of the example's variables as images."""
    from matplotlib.figure import Figure
    from sphinx_gallery.scrapers import figure_rst

    figures = []
    for value in block_vars["example_globals"].values():
        if not isinstance(value, Figure) or value in _SHOWN:
            continue
        _SHOWN.add(value)
        # a pyplot figure is the matplotlib scraper's (which runs after this
        # one and closes it, dropping its manager)
        if getattr(value.canvas, "manager", None) is None:
            figures.append(value)
    paths = []
    for figure, path in zip(figures, block_vars["image_path_iterator"]):
        figure.savefig(path, dpi=100)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
