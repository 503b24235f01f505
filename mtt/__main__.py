from mtt.cli.main import main

raise SystemExit(main())
