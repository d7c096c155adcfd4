# GeoFusion: the two commands a user needs.
#   make demo   install what is missing, build, and run the demo
#   make test   install what is missing, build, and run every test (exit code = result)
.PHONY: demo test deps build lint clean help

help:
	@sed -n '2,4p' Makefile

deps:
	@scripts/install_deps.sh

build: deps
	@scripts/build.sh

test: build
	@scripts/test.sh

demo: build
	@scripts/demo.sh

lint:
	@scripts/lint.sh

clean:
	@bash -c 'source scripts/env.sh && echo "[geofusion] removing $$GEOFUSION_WS" && rm -rf "$$GEOFUSION_WS"'
