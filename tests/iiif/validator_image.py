"""The IIIF validator's test image, drawn from the validator's own colour table: 1000 x 1000
pixels, 10 x 10 squares of 100 px, square (x, y) filled with colorInfo[x][y] (x the column,
y the row). The published image also prints each square's coordinates in it; the validator
reads the square's dominant colour, which the fill alone gives.

usage: validator_image.py OUT.png
"""
import sys

from PIL import Image
from iiif_validator.validator import ValidationInfo


def main(out):
    colours = ValidationInfo().colorInfo
    img = Image.new("RGB", (1000, 1000))
    px = img.load()
    for x in range(10):
        for y in range(10):
            c = tuple(colours[x][y])
            for j in range(y * 100, y * 100 + 100):
                for i in range(x * 100, x * 100 + 100):
                    px[i, j] = c
    img.save(out)


if __name__ == "__main__":
    main(sys.argv[1])
