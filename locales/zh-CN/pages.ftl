# enact-hub 页面，简体中文。每个键都必须与 locales/en/pages.ftl 一一对应。

## 每个页面的框架
nav-label = 站点
nav-datasets = 数据集
nav-studies = 研究
nav-annotate = 标注
footer = enact-hub · ENACT 具身世界建模基准的评测服务

## 错误页面
error-detail = 详细信息（系统原文，英文）：
error-back = 返回数据集
error-reason-400 = 请求有误
error-explain-400 = 无法理解该请求：其中有内容缺失或格式不正确。
error-reason-401 = 未登录
error-explain-401 = 您尚未登录，或会话已过期。
error-reason-403 = 禁止访问
error-explain-403 = 您无权执行此操作。
error-reason-404 = 未找到
error-explain-404 = 此处没有内容：该页面、数据集或条目不存在。
error-reason-409 = 冲突
error-explain-409 = 该操作与已保存的内容冲突。
error-reason-413 = 内容过大
error-explain-413 = 发送的内容超出了本服务接受的大小。
error-reason-415 = 不支持的格式
error-explain-415 = 发送的内容不是本服务能读取的格式。
error-reason-422 = 内容无效
error-explain-422 = 发送的内容已读取，但其中部分内容无效。
error-reason-429 = 请求过多
error-explain-429 = 尝试次数过多：请稍候再试。
error-reason-500 = 服务器内部错误
error-explain-500 = 服务端出现问题，已记录在日志中。
error-reason-503 = 服务暂不可用
error-explain-503 = 本服务暂时无法完成此操作：请稍后再试。

## 登录
login-title = 登录
login-heading = 登录以进行标注
login-name = 用户名
login-password = 密码
login-submit = 登录
login-no-account = 还没有账号？请由管理员创建账号，并向您发送一次性邀请链接。
login-error-expired = 登录表单已过期或缺少 CSRF 令牌：请重试
login-error-missing = 请填写用户名和密码
login-error-wrong = 用户名不存在或密码错误
login-error-limited = 登录失败次数过多：请在 { $minutes } 分钟后重试

## 标注队列
queue-title = 我的队列
queue-logged-in-as = 当前登录：
queue-admin = 管理
queue-log-out = 退出登录
queue-finished = 已完成 { $done } / { $total } 个条目。
queue-resume = 从上次中断处继续
queue-continue = 继续
queue-all-done = 分配给您的条目已全部完成，谢谢！
queue-empty = 目前还没有分配给您的条目。
queue-progress-caption = 已完成 / 已分配，按方向和步长统计（L = 图像数量）

## 表头与基准术语
col-direction = 方向
col-item = 条目
col-dataset = 数据集
col-status = 状态
direction-forward = 正向
direction-inverse = 逆向
status-todo = 待完成
status-started = 进行中
status-answered = 已作答
status-skipped = 已跳过
status-flagged = 已标记问题

## 标注页面（正向与逆向）
annotate-title-forward = 正向条目
annotate-title-inverse = 逆向条目
annotate-task-forward = 正向世界建模：按动作产生的顺序排列未来图像
annotate-task-inverse = 逆向世界建模：为每个状态转变选出导致它的动作
annotate-instructions = 说明（模型收到的题目原文）
annotate-untranslated = 题目按模型收到的原样以英文显示，不做翻译：它是基准的一部分。
annotate-untranslated-actions = 动作描述是基准的一部分，按数据集中的原文显示，不做翻译。
annotate-finished = 您已完成此条目。
annotate-next = 继续下一个
annotate-answer = 答案
annotate-steps = 步骤：第 k 个动作得到第 k 张图像
annotate-transitions = 状态转变（按顺序）
annotate-enlarge = 放大 { $name }
annotate-alt-current = 当前状态，动作由此开始（{ $name }）
annotate-current-caption = { $name }：动作由此开始
annotate-alt-before = 第 { $index } 个转变，之前的状态（{ $name }）
annotate-alt-after = 第 { $index } 个转变，之后的状态（{ $name }）
annotate-alt-candidate = 候选 { $name }
annotate-undo = 撤销
annotate-submit = 提交答案
annotate-candidate-images = 候选图像
annotate-candidate-actions = 候选动作
annotate-shuffled = （已打乱）
annotate-keyboard-help = 将卡片拖到槽位上，或先点击卡片再点击槽位。键盘操作：方向键在槽位和卡片之间移动（检视区随之更新）；在卡片上按槽位编号即可放入；在槽位或已放置的卡片上按 Backspace 清除；把卡片放到已占用的槽位会交换位置；Ctrl+Z 或“撤销”按钮可撤销。
annotate-inspector = 检视区：放大显示当前焦点所在的图像
annotate-inspector-hint = 将指针移到图像上或让图像获得焦点，即可在此放大查看。
annotate-skip-summary = 跳过此条目或报告问题
annotate-reason = 原因
annotate-skip = 跳过
annotate-flag = 报告问题
annotate-lightbox = 放大的图像
annotate-close = 关闭

## 标注页面脚本的提示（实时播报区、状态、标签）
js-slot-empty = 槽位 { $slot }：空
js-slot-filled = 槽位 { $slot }：{ $name }
js-card-in-slot = 在槽位 { $slot }
js-saving = 正在保存…
js-saved = 已保存
js-not-saved = 未保存：{ $error }
js-placed = { $name } 已放入槽位 { $slot }。
js-swapped-moved = { $name } 已移到槽位 { $slot }。
js-swapped-returned = { $name } 已放回候选区。
js-cleared = 槽位 { $slot } 已清空；{ $name } 已放回候选区。
js-nothing-to-undo = 没有可撤销的操作。
js-undone = 已撤销。
js-card-selected = 已选中 { $name }：请选择槽位。
js-no-such-slot = 没有槽位 { $key }；槽位编号为 1 到 { $count }。
js-slot-selected = 已选中 { $name }：请选择另一个槽位以移动它。
js-submitted = 答案已提交。
js-not-submitted = 未提交：{ $error }
js-before-start = 之前：{ $name }
js-before-empty = 之前：槽位 { $slot } 为空
js-before-slot = 之前：槽位 { $slot }，{ $name }
js-focus-slot-empty = 槽位 { $slot }：空
js-focus-slot = 槽位 { $slot }：{ $name }
js-transition-before = 第 { $index } 个转变，之前：{ $name }
js-transition-after = 第 { $index } 个转变，之后：{ $name }
js-not-placed = { $name }（未放置）

## 首页：数据集
home-submitting = 要提交模型结果？请参阅
home-api-docs = API 文档。
home-empty = 此数据库中还没有数据集。
home-import = 导入一个 ENACT 发布版本（包含 QA/enact_ordering.jsonl 及其图像的文件夹）：
home-demo = 或者使用内置的演示数据集启动服务：
home-items-from-tasks = { $items } 个条目，来自 { $tasks } 个任务
home-imported = 导入于 { $date }
home-leaderboard = 排行榜
home-counts-caption = 按方向和步长统计的条目数（L = 图像数量）
col-all = 全部
col-step-length = 步长
col-task = 任务

## 数据集的条目
dataset-download = 以 ENACT 发布归档（tar）下载全部条目
dataset-download-what = — 包括 QA/enact_ordering.jsonl 和图像。仅当该数据集的答案公开时才包含答案。
dataset-any = 任意
dataset-show = 显示
dataset-no-match = 没有符合这些筛选条件的条目。
dataset-shown = 第 { $first }–{ $last } 项，共 { $total } 项
pager-label = 分页
pager-previous = 上一页
pager-next = 下一页

## 单个条目（只读）
item-crumb = 条目
item-counts = { $images } 张图像，{ $actions } 个动作
item-type = 类型
item-images = 图像
item-images-forward = （先是当前状态，然后是条目中打乱顺序的未来状态）
item-images-inverse = （按时间顺序）
item-alt-image = 条目中位置 { $position } 的图像（{ $name }）
item-actions = 动作
item-actions-forward = （按顺序）
item-question = 完整题目文本（与模型收到的相同）
