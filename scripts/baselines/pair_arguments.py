"""The command line every baseline of scripts/register_task.py shares: the fixed image, the
moving image and where the field goes (the runner's {fixed}, {moving} and {output})."""

import argparse


def pair_parser(description):
    parser = argparse.ArgumentParser(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fixed", help="the fixed image (NIfTI)")
    parser.add_argument("moving", help="the moving image, on the fixed image's grid for a Learn2Reg pair")
    parser.add_argument("output", help="the displacement field to write, on the fixed grid")
    return parser
