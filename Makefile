# Common tasks. The README's two quick-start commands do not need make.
.PHONY: install demo test lint format bench

install:
	pip install -e ".[all]"

demo:
	fetchcarry demo --out episode.png

test:
	python -m pytest -n 2

lint:
	ruff check . && ruff format --check .

format:
	ruff check --fix . && ruff format .

bench:
	fetchcarry bench env
	fetchcarry bench planner
