from mtt.cli import main

raise SystemExit(main())
