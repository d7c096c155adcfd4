# GeoFusion: the two commands a user needs.
#   make demo   install what is missing, build, and run the demo
#   make test   install what is missing, build, and run every test (exit code = result)
#   make data SUITE=demo|bench   generate (or reuse) a data suite in ~/.cache/geofusion/data
.PHONY: demo test data deps build lint clean help

help:
	@sed -n '2,5p' Makefile

deps:
	@bash scripts/install_deps.sh

build: deps
	@bash scripts/build.sh

test: build
	@bash scripts/test.sh

demo: build
	@bash scripts/demo.sh

data: build
	@bash scripts/data.sh

lint:
	@bash scripts/lint.sh

clean:
	@bash -c 'source scripts/env.sh && echo "[geofusion] removing $$GEOFUSION_WS" && rm -rf "$$GEOFUSION_WS"'
