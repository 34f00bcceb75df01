"""Order of the example gallery: from the first steps to the whole workflow.

sphinx-gallery takes the sort key by its importable name (conf.py puts this
folder on ``sys.path``), which keeps the configuration picklable for
Sphinx's cache.
"""

ORDER = [
    "plot_getting_started.py",
    "plot_bla_bouc_wen.py",
    "plot_odd_even_detection.py",
    "plot_pnlss_bouc_wen.py",
    "plot_decoupled_bouc_wen.py",
    "plot_grid_search_selection.py",
    "plot_dask_search.py",
    "plot_gap_diagnosis.py",
    "plot_f16_gvt.py",
    "plot_gap_f16.py",
    "plot_field_benchmarks.py",
]


class GalleryOrder:
    """Sort key: the examples of ``ORDER`` in that order, any other after
    them by file name."""

    def __init__(self, src_dir):
        self.src_dir = src_dir

    def __call__(self, filename):
        name = str(filename).rsplit("/", 1)[-1]
        return (ORDER.index(name) if name in ORDER else len(ORDER), name)

    def __repr__(self):
        return "GalleryOrder"
