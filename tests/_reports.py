"""Reports written by tests that read only their tables, text and file names, not their pictures."""

#: What an undrawn figure's file holds: PNG's signature (report.html embeds it like any PNG).
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def undrawn_figures(monkeypatch) -> None:
    """Have ``Figure.savefig`` write :data:`PNG_SIGNATURE` instead of laying the figure out and rasterising it.

    The figures are still built (``plot_heatmap``, ``plot_fronts``, ``plot_scatter`` run with the report's data,
    titles and structures); only their drawing is skipped, which is most of a report's time (constrained layout and
    text extents: about 1 s of CPU a report of two data sets). For tests whose assertions read the report's CSV,
    summary.txt or file names; the tests of the figures themselves (test_experiments' test_figures_and_report_files,
    test_hunt43a's band_report, test_hunt38c, test_hunt45g, the titles-inside tests) draw them."""
    from matplotlib.figure import Figure

    def savefig(self, fname, *args, **kwargs):
        if hasattr(fname, "write"):
            fname.write(PNG_SIGNATURE)
        else:
            with open(fname, "wb") as f:
                f.write(PNG_SIGNATURE)

    monkeypatch.setattr(Figure, "savefig", savefig)
