"""The command of the grazing-view study (issue 24, docs/grazing-fit.md):

    python3 studies/grazing_fit.py --out DIR [--quick] [--alpha A]

Owns only the command's path; the study is the package studies/grazing/ (its __init__ has the model,
equations and citations). Calls grazing.report.main."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from grazing.report import main  # noqa: E402

if __name__ == "__main__":
    main()
