"""The report's figures. Importing this package registers them; the import order below is the
order of the figures in the report."""
from rotorsweep.pipeline.report.figures import stability_map  # noqa: F401  (registers itself)
from rotorsweep.pipeline.report.figures import atlas  # noqa: F401
from rotorsweep.pipeline.report.figures import branch_diagram  # noqa: F401
from rotorsweep.pipeline.report.figures import max_multiplier  # noqa: F401
from rotorsweep.pipeline.report.figures import response  # noqa: F401
from rotorsweep.pipeline.report.figures import bode  # noqa: F401
from rotorsweep.pipeline.report.figures import multiplier_frequency  # noqa: F401
from rotorsweep.pipeline.report.figures import mode_campbell  # noqa: F401
from rotorsweep.pipeline.report.figures import mode_shapes  # noqa: F401
from rotorsweep.pipeline.report.figures import multiplier_paths  # noqa: F401
from rotorsweep.pipeline.report.figures import bifurcation  # noqa: F401
from rotorsweep.pipeline.report.figures import lle  # noqa: F401
