"""Applications on top of the recipes: the interactive explorer and the demo."""
